#include "local_render.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "lf/core/aov.h"
#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/scene_loader.h"
#include "lf/job/job_spec.h"
#include "lf/job/render_metadata.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/frame_renderer.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/ray_tracer.h"
#include "lf/kernels/whitted.h"
#include "method_choice.h"
#include "output_flags.h"
#include "progress_bar.h"
#include "radiosity_flags.h"

namespace lf {

absl::StatusOr<std::string> ChooseMethod(const Scene& scene, const std::string& requested,
                                         std::string* why) {
    if (requested != "auto") {
        // The job model's names, or unknown.
        if (std::string error = MethodFlagError(requested, true); !error.empty()) {
            return absl::Status(CheckMethod(requested).code(), "--" + error);
        }
        *why = "requested";
        return requested;
    }
    MethodChoice choice = ChooseAutomatically(scene);
    *why = std::move(choice.why);
    return choice.method;
}

std::string MethodFlagError(const std::string& method, bool allow_auto) {
    if (allow_auto && method == "auto") return "";
    const absl::Status s = CheckMethod(method);
    if (s.ok()) return "";
    std::string message(s.message());
    const std::string expected = "expected one of ";
    if (const size_t at = message.find(expected); allow_auto && at != std::string::npos) {
        message.insert(at + expected.size(), "auto, ");
    }
    return message;
}

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options) {
    for (const std::string* path : {&options.exr_path, &options.png_path}) {
        if (absl::Status s = CheckWritable(*path); !s.ok()) return s;
    }
    auto log = NamedLogger("render");
    const absl::Time start = absl::Now();

    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    const std::string job_id = "local-" + scene->content_hash.substr(0, 8);
    std::string why;
    absl::StatusOr<std::string> method = ChooseMethod(*scene, options.method, &why);
    if (!method.ok()) return method.status();
    log->info("job={} method {} ({})", job_id, *method, why);

    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    LocalRenderSummary summary;
    summary.load_seconds = absl::ToDoubleSeconds(absl::Now() - start);

    std::unique_ptr<RadianceEstimator> estimator;
    std::unique_ptr<FrameRenderer> frame_renderer;  // light, bdpt, ppm
    std::optional<FramePlanSettings> frame_plan;
    const RadiosityRenderer* radiosity = nullptr;
    const bool adaptive = options.adaptive.target_error > 0 || options.adaptive.time_limit > 0;
    if (UsesFramePlan(*method)) {
        // The job model's checks, so local mode refuses what the coordinator refuses.
        if (options.render.aovs != 0 || adaptive) {
            JobSpec spec;
            spec.method = *method;
            spec.aovs = options.render.aovs;
            spec.adaptive = options.adaptive;
            if (absl::Status s = CheckJobSettings(spec); !s.ok()) return s;
        }
        if (absl::Status s = CheckPhotonSettings(options.ppm); !s.ok()) return s;
        absl::StatusOr<FramePlanSettings> plan =
            FramePlanSettingsOf(*method, {camera.width(), camera.height(), options.render.spp,
                                          options.render.tile, options.render.passes});
        if (!plan.ok()) return plan.status();
        frame_plan = *plan;
        absl::StatusOr<std::unique_ptr<FrameRenderer>> made = MakeFrameRenderer(
            *method, **embree, camera,
            FrameRenderSettingsOf<FrameRenderSettings>(options.max_depth, options.render.seed,
                                                       options.render.sampler, options.render.clamp,
                                                       options.render.light_strategy, options.ppm));
        if (!made.ok()) return made.status();
        frame_renderer = std::move(*made);
    } else if (*method == "radiosity") {
        absl::StatusOr<RadiosityOptions> parsed = RadiosityOptionsOf(options.radiosity);
        if (!parsed.ok()) return parsed.status();
        RadiosityOptions ro = *parsed;
        ro.save_solution = options.save_solution;
        ro.load_solution = options.load_solution;
        ro.export_ply = options.export_ply;
        ro.threads = options.render.threads;
        // The one --target-error bounds both errors: the mesh's and the display's sampling.
        ro.target_error = options.adaptive.target_error;
        const absl::Time solve_start = absl::Now();
        absl::StatusOr<std::unique_ptr<RadiosityRenderer>> r = PrepareRadiosity(**embree, ro);
        if (!r.ok()) return r.status();
        radiosity = r->get();
        estimator = std::move(*r);
        const RadiosityReport& rep = radiosity->report();
        summary.radiosity_seconds = absl::ToDoubleSeconds(absl::Now() - solve_start);
        summary.radiosity = RadiosityFiguresOf(rep);
        summary.mesh_seconds = rep.mesh_seconds;
        log->info(
            "job={} radiosity: {} patches, {} unknowns, {} iterations, residual {:.2e}, form "
            "factors {:.2f} s ({} MiB), solve {:.2f} s",
            job_id, rep.patches, rep.sides, rep.iterations, rep.residual, rep.form_factor_seconds,
            rep.form_factor_bytes >> 20, rep.solve_seconds);
        for (size_t pass = 0; pass < rep.refinement.size(); ++pass) {
            const RadiosityRefinementPass& p = rep.refinement[pass];
            log->info(
                "job={} radiosity refinement pass {}: {} patches, {} unknowns, form factors "
                "{:.2f} s ({} pairs evaluated, {} reused), estimated error max {:.3g} mean "
                "{:.3g}, {} cells split",
                job_id, pass + 1, p.patches, p.sides, p.form_factor_seconds, p.pairs,
                p.reused_pairs, p.max_error, p.mean_error, p.split);
        }
        if (ro.target_error > 0) {
            log->info("job={} radiosity refinement: estimated error {:.3g} (target {:.3g}){}{}",
                      job_id, rep.estimated_error, ro.target_error,
                      rep.budget_reached ? ", stopped by the patch budget" : "",
                      rep.finest_above_target > 0
                          ? absl::StrCat(", ", rep.finest_above_target,
                                         " patches above it at the finest level")
                          : std::string());
        }
    } else {
        absl::StatusOr<std::unique_ptr<RadianceEstimator>> tracer =
            MakeRayTracer(*method, **embree, options.max_depth, options.render.light_strategy);
        if (!tracer.ok()) return tracer.status();
        estimator = std::move(*tracer);
        if (*method == "whitted") {
            for (const std::string& term : WhittedMissingTerms(*scene)) {
                log->info("job={} whitted leaves out {}", job_id, term);
            }
        }
    }
    log->info(
        "job={} rendering {} ({}x{}, {} spp, {} sampler{}, seed {}, max depth {}, tile {}, {} "
        "filter{}{})",
        job_id, options.scene_path, camera.width(), camera.height(), options.render.spp,
        SamplerTypeName(options.render.sampler),
        IsRayTracingMethod(*method)
            ? absl::StrCat(", ", LightStrategyName(options.render.light_strategy),
                           " light sampling")
            : std::string(),
        options.render.seed,
        options.max_depth >= 0 ? std::to_string(options.max_depth)
        : *method == "whitted"
            ? absl::StrCat("unlimited (whitted: ", kWhittedUnlimitedDepth, " specular bounces)")
            : "unlimited",
        options.render.tile, DescribePixelFilter(scene->camera.filter),
        options.render.clamp > 0 ? absl::StrCat(", clamp ", options.render.clamp, " (biased)")
                                 : std::string(),
        options.render.aovs != 0 ? ", AOVs " + AovListName(options.render.aovs) : std::string());
    if (frame_plan) {
        log->info(
            "job={} {}", job_id,
            frame_plan->kind == FramePlanKind::kLightPaths
                ? absl::StrCat(frame_plan->light_paths, " light paths in ranges of ",
                               frame_plan->max_paths_per_task)
            : frame_plan->kind == FramePlanKind::kPhotonPasses
                ? absl::StrCat(frame_plan->spp, " photon passes of ", options.ppm.photons_per_pass,
                               " photons, alpha ", options.ppm.alpha, ", first radius ",
                               options.ppm.initial_radius > 0
                                   ? absl::StrCat(options.ppm.initial_radius)
                                   : std::string("the kernel's choice"),
                               ", tile ", frame_plan->tile)
                : std::string("a light subpath per camera sample"));
    }
    if (adaptive) {
        log->info(
            "job={} adaptive: first pass {} spp, target error {}, time limit {} s, at "
            "most {} spp",
            job_id, options.render.spp, options.adaptive.target_error, options.adaptive.time_limit,
            options.adaptive.max_spp);
    }
    ProgressBar bar("render");
    const ProgressFn progress = [&](size_t done, size_t n) {
        if (options.progress) bar.Update(done, n);
    };
    absl::StatusOr<RenderOutput> out =
        frame_renderer
            ? RenderFrameImage(camera, *frame_renderer, *frame_plan, options.render, progress)
        : adaptive
            ? RenderImageAdaptive(camera, *estimator, options.render, options.adaptive, progress)
            : RenderImage(camera, *estimator, options.render, progress);
    if (options.progress) bar.Finish();
    if (!out.ok()) return out.status();
    if (out->stats.invalid_samples > 0) {
        log->warn("job={} {} NaN or infinite samples were discarded (counted as zero)", job_id,
                  out->stats.invalid_samples);
    }

    if (out->stats.truncated_paths > 0 && *method == "whitted") {
        log->warn(
            "job={} {} specular rays reached whitted's depth cap of {} and were cut (--max-depth "
            "sets it)",
            job_id, out->stats.truncated_paths, kWhittedUnlimitedDepth);
    } else if (out->stats.truncated_paths > 0) {
        log->warn(
            "job={} {} paths reached the depth cap of {} bounces and were cut (a "
            "reflectance of 1 keeps Russian roulette from ending them)",
            job_id, out->stats.truncated_paths, kMaxPathDepth);
    }

    summary.job_id = job_id;
    summary.method = *method;
    summary.stats = out->stats;
    summary.render_seconds = out->seconds;
    summary.width = camera.width();
    summary.height = camera.height();
    summary.adaptive = adaptive;
    summary.adaptive_report = out->adaptive;
    summary.seconds = absl::ToDoubleSeconds(absl::Now() - start);

    RenderMetadata metadata;
    metadata.scene_hash = scene->content_hash;
    metadata.camera = options.scene.camera;
    metadata.method = *method;
    metadata.spp = adaptive ? out->adaptive.max_spp : options.render.spp;
    metadata.seed = options.render.seed;
    metadata.max_depth = options.max_depth;
    metadata.clamp = options.render.clamp;
    metadata.aovs = options.render.aovs;
    metadata.sampler = options.render.sampler;
    metadata.light_strategy = options.render.light_strategy;
    metadata.filter = scene->camera.filter;
    metadata.seconds = summary.seconds;
    metadata.stats = out->stats;
    metadata.adaptive_settings = options.adaptive;
    if (adaptive) metadata.adaptive = out->adaptive;
    metadata.radiosity_settings = options.radiosity;
    metadata.radiosity = summary.radiosity;
    metadata.ppm = options.ppm;
    absl::StatusOr<RenderDescription> description = DescribeRender(metadata, out->image, true);
    if (!description.ok()) return description.status();
    if (description->estimates) {
        const VarianceAssessment& variance = description->estimates->variance;
        summary.estimated_error = description->estimates->estimated_error;
        summary.estimated_relmse = variance.relmse;
        summary.high_variance = variance.high;
        log->info(
            "job={} estimated relative error {:.4f}, estimated relMSE {:.3g}, error of the mean "
            "{:.3g}",
            job_id, summary.estimated_error, variance.relmse, variance.mean_error);
        if (summary.high_variance) {
            log->warn(
                "job={} high variance: estimated relMSE {:.3g} (limit {}: a typical pixel off by "
                "{:.0f} %), relative error of the mean radiance {:.3g} (limit {})",
                job_id, variance.relmse, kHighVarianceRelMse, 100 * std::sqrt(variance.relmse),
                variance.mean_error, kHighVarianceMeanError);
        }
    }
    if (!options.exr_path.empty()) {
        const ExrAttributes& attributes = description->attributes;
        if (absl::Status s = WriteExr(options.exr_path, out->image, attributes); !s.ok()) return s;
    }
    if (!options.png_path.empty()) {
        if (absl::Status s = WritePng(options.png_path, out->image, options.preview); !s.ok()) {
            return s;
        }
    }
    return summary;
}

}  // namespace lf
