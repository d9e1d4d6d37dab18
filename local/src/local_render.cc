#include "lf/local/local_render.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "lf/core/aov.h"
#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/plural.h"
#include "lf/core/scene_loader.h"
#include "lf/job/job_spec.h"
#include "lf/job/render_metadata.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/whitted.h"
#include "lf/local/method_choice.h"
#include "lf/local/method_factory.h"

namespace lf {

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options) {
    auto log = NamedLogger("render");
    const absl::Time start = absl::Now();

    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    const std::string job_id = "local-" + scene->content_hash.substr(0, 8);
    const MethodChoice choice = ChooseMethod(*scene, options.method);
    const Method method = choice.method;
    const MethodInfo& info = Info(method);
    log->info("job={} method {} ({})", job_id, info.name, choice.why);

    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    LocalRenderSummary summary;
    summary.load_seconds = absl::ToDoubleSeconds(absl::Now() - start);

    std::unique_ptr<RadianceEstimator> estimator;
    std::unique_ptr<SplatRenderer> splat_renderer;  // light, bdpt, ppm
    std::optional<SplatPlanSettings> splat_plan;
    const RadiosityRenderer* radiosity = nullptr;
    const bool adaptive = options.adaptive.target_error > 0 || options.adaptive.time_limit > 0;
    // The job this render is, as the farm would run it: its kernels' settings and its header.
    JobSpec job;
    job.method = std::string(info.name);
    job.scene_options = options.scene;
    job.scene_options.filter = scene->camera.filter;
    job.plan = {camera.width(), camera.height(), options.render.spp, options.render.tile,
                options.render.passes};
    job.seed = options.render.seed;
    job.max_depth = options.max_depth;
    job.clamp = options.render.clamp;
    job.aovs = options.render.aovs;
    job.sampler = options.render.sampler;
    job.light_strategy = options.render.light_strategy;
    job.radiosity = options.radiosity;
    job.ppm = options.ppm;
    job.adaptive = options.adaptive;
    job.scene_hash = scene->content_hash;
    if (info.work == WorkKind::kSplatPasses) {
        // The job model's checks, so local mode refuses what the coordinator refuses.
        if (options.render.aovs != 0 || adaptive) {
            JobSpec spec;
            spec.method = job.method;
            spec.aovs = options.render.aovs;
            spec.adaptive = options.adaptive;
            if (absl::Status s = CheckJobSettings(spec); !s.ok()) return s;
        }
        if (absl::Status s = CheckPhotonSettings(options.ppm); !s.ok()) return s;
        absl::StatusOr<SplatPlanSettings> plan = SplatPlanSettingsOf(job.method, job.plan);
        if (!plan.ok()) return plan.status();
        splat_plan = *plan;
        absl::StatusOr<std::unique_ptr<SplatRenderer>> made =
            MakeSplatRenderer(method, **embree, camera, SplatRenderSettingsOf(job));
        if (!made.ok()) return made.status();
        splat_renderer = std::move(*made);
    } else if (info.work == WorkKind::kRadiosity) {
        // The one --target-error bounds both errors: the mesh's and the display's sampling.
        absl::StatusOr<RadiosityOptions> parsed =
            RadiosityOptionsOf(options.radiosity, options.adaptive.target_error);
        if (!parsed.ok()) return parsed.status();
        RadiosityOptions ro = *parsed;
        ro.save_solution = options.save_solution;
        ro.load_solution = options.load_solution;
        ro.export_ply = options.export_ply;
        ro.threads = options.render.threads;
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
            "job={} radiosity: {} patches, {} unknowns, {}, residual {:.2e}, form "
            "factors {:.2f} s ({} MiB), solve {:.2f} s",
            job_id, rep.patches, rep.sides, Plural(rep.iterations, "iteration"), rep.residual,
            rep.form_factor_seconds, rep.form_factor_bytes >> 20, rep.solve_seconds);
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
            MakeRayTracer(method, **embree, options.max_depth, options.render.light_strategy);
        if (!tracer.ok()) return tracer.status();
        estimator = std::move(*tracer);
        if (method == Method::kWhitted) {
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
        info.work == WorkKind::kTiles
            ? absl::StrCat(", ", LightStrategyName(options.render.light_strategy),
                           " light sampling")
            : std::string(),
        options.render.seed,
        options.max_depth >= 0 ? std::to_string(options.max_depth)
        : method == Method::kWhitted
            ? absl::StrCat("unlimited (whitted: ", kWhittedUnlimitedDepth, " specular bounces)")
            : "unlimited",
        options.render.tile, DescribePixelFilter(scene->camera.filter),
        options.render.clamp > 0 ? absl::StrCat(", clamp ", options.render.clamp, " (biased)")
                                 : std::string(),
        options.render.aovs != 0 ? ", AOVs " + AovListName(options.render.aovs) : std::string());
    log->info("job={} camera: {}", job_id, DescribeCamera(scene->camera));
    if (splat_plan) {
        log->info(
            "job={} {}", job_id,
            splat_plan->kind == SplatPlanKind::kLightPaths
                ? absl::StrCat(splat_plan->light_paths, " light paths in ranges of ",
                               splat_plan->max_paths_per_task)
            : splat_plan->kind == SplatPlanKind::kPhotonPasses
                ? absl::StrCat(splat_plan->spp, " photon passes of ", options.ppm.photons_per_pass,
                               " photons, alpha ", options.ppm.alpha, ", first radius ",
                               options.ppm.initial_radius > 0
                                   ? absl::StrCat(options.ppm.initial_radius)
                                   : std::string("the kernel's choice"),
                               ", tile ", splat_plan->tile)
                : std::string("a light subpath per camera sample"));
    }
    if (adaptive) {
        log->info(
            "job={} adaptive: first pass {} spp, target error {}, time limit {} s, at "
            "most {} spp",
            job_id, options.render.spp, options.adaptive.target_error, options.adaptive.time_limit,
            options.adaptive.max_spp);
    }
    if (options.progress) options.progress->Start();
    const ProgressFn progress = [&](size_t done, size_t n) {
        if (options.progress) options.progress->Update(done, n);
    };
    const std::atomic<bool>* interrupt =
        options.interrupt && !splat_renderer ? &options.interrupt->requested : nullptr;
    if (interrupt) options.interrupt->honoured = true;
    absl::StatusOr<RenderOutput> out =
        splat_renderer
            ? RenderSplatImage(camera, *splat_renderer, *splat_plan, options.render, progress)
        : adaptive ? RenderImageAdaptive(camera, *estimator, options.render, options.adaptive,
                                         progress, {}, interrupt)
                   : RenderImage(camera, *estimator, options.render, progress, interrupt);
    if (interrupt) options.interrupt->honoured = false;
    if (options.progress) options.progress->Finish();
    if (!out.ok()) return out.status();
    if (out->interrupted) {
        summary.partial = absl::StrCat(
            "interrupted after ", out->tasks_done, " of ", out->task_count,
            " tasks (whole passes of tiles): each pixel is the mean of its own samples, the spp "
            "channel (0 where none ran)");
        log->warn("job={} {}", job_id, summary.partial);
    }
    if (out->stats.invalid_samples > 0) {
        log->warn("job={} {} NaN or infinite samples were discarded (counted as zero)", job_id,
                  out->stats.invalid_samples);
    }

    if (out->stats.truncated_paths > 0 && method == Method::kWhitted) {
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
    summary.method = method;
    summary.stats = out->stats;
    summary.render_seconds = out->seconds;
    summary.width = camera.width();
    summary.height = camera.height();
    summary.adaptive = adaptive;
    summary.adaptive_report = out->adaptive;
    summary.seconds = absl::ToDoubleSeconds(absl::Now() - start);

    RenderOutcome outcome;
    outcome.seconds = summary.seconds;
    outcome.stats = out->stats;
    if (adaptive) outcome.adaptive = out->adaptive;
    outcome.radiosity = summary.radiosity;
    outcome.partial = summary.partial;
    // A partial image's A/B halves are not a whole render's: no error estimate.
    absl::StatusOr<RenderDescription> description =
        DescribeRender(MetadataOf(job, outcome), out->image, !out->interrupted);
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
