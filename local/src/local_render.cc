#include "lf/local/local_render.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "lf/core/aov.h"
#include "lf/core/camera.h"
#include "lf/core/false_color.h"
#include "lf/core/image_error.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/plural.h"
#include "lf/core/scene_animation.h"
#include "lf/core/scene_loader.h"
#include "lf/job/job_spec.h"
#include "lf/job/render_metadata.h"
#include "lf/job/shot.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/scene_motion.h"
#include "lf/kernels/whitted.h"
#include "lf/local/method_choice.h"
#include "lf/local/method_factory.h"

namespace lf {

namespace {

// The kernels one pose of the scene renders with: its BVH, its camera and the method's estimator
// or splat renderer (radiosity: the solved mesh). Built in place, as the renderers hold
// references to the BVH and the camera.
struct PosedKernels {
    std::unique_ptr<EmbreeScene> embree;
    std::optional<Camera> camera;
    std::unique_ptr<RadianceEstimator> estimator;
    std::unique_ptr<SplatRenderer> splat_renderer;  // light, bdpt, ppm
    double bvh_seconds = 0;
    double radiosity_seconds = 0, mesh_seconds = 0;
    std::optional<RadiosityFigures> radiosity;
};

bool IsAdaptive(const LocalRenderOptions& options) { return IsAdaptive(options.adaptive); }

// The job a render of `scene` is, as the farm would run it: its kernels' settings and its header.
JobSpec LocalJobOf(const LocalRenderOptions& options, const Scene& scene, const MethodInfo& info) {
    JobSpec job;
    job.method = std::string(info.name);
    job.scene_options = options.scene;
    job.scene_options.filter = scene.camera.filter;
    job.plan = {scene.camera.width, scene.camera.height, options.render.spp, options.render.tile,
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
    job.scene_hash = scene.content_hash;
    return job;
}

// The splatting methods' plan, after the job model's checks, so that local mode refuses what
// the coordinator refuses (AOVs and adaptive sampling of methods without them, for every
// method); nullopt for the other methods.
absl::StatusOr<std::optional<SplatPlanSettings>> SplatPlanOf(const LocalRenderOptions& options,
                                                             const JobSpec& job,
                                                             const MethodInfo& info) {
    if (options.render.aovs != 0 || IsAdaptive(options)) {
        JobSpec spec;
        spec.method = job.method;
        spec.aovs = options.render.aovs;
        spec.adaptive = options.adaptive;
        if (absl::Status s = CheckJobSettings(spec); !s.ok()) return s;
    }
    if (info.work != WorkKind::kSplatPasses) return std::nullopt;
    if (absl::Status s = CheckPhotonSettings(options.ppm); !s.ok()) return s;
    absl::StatusOr<SplatPlanSettings> plan = SplatPlanSettingsOf(job.method, job.plan);
    if (!plan.ok()) return plan.status();
    return *plan;
}

// Builds the BVH of `scene` as it is posed now (and over the shutter of `motion`, when it
// blurs) and the kernels of `method` on it.
absl::StatusOr<std::unique_ptr<PosedKernels>> BuildKernels(const Scene& scene,
                                                           const LocalRenderOptions& options,
                                                           Method method, const JobSpec& job,
                                                           const std::string& job_id,
                                                           const SceneMotion& motion = {}) {
    auto log = NamedLogger("render");
    auto k = std::make_unique<PosedKernels>();
    const absl::Time bvh_start = absl::Now();
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree =
        EmbreeScene::Build(scene, nullptr, motion);
    if (!embree.ok()) return embree.status();
    k->embree = std::move(*embree);
    k->bvh_seconds = absl::ToDoubleSeconds(absl::Now() - bvh_start);
    k->camera.emplace(scene.camera, k->embree->origin(), k->embree->camera_motion());
    const MethodInfo& info = Info(method);
    if (info.work == WorkKind::kSplatPasses) {
        absl::StatusOr<std::unique_ptr<SplatRenderer>> made =
            MakeSplatRenderer(method, *k->embree, *k->camera, SplatRenderSettingsOf(job));
        if (!made.ok()) return made.status();
        k->splat_renderer = std::move(*made);
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
        absl::StatusOr<std::unique_ptr<RadiosityRenderer>> r = PrepareRadiosity(*k->embree, ro);
        if (!r.ok()) return r.status();
        const RadiosityReport& rep = (*r)->report();
        k->estimator = std::move(*r);
        k->radiosity_seconds = absl::ToDoubleSeconds(absl::Now() - solve_start);
        k->radiosity = RadiosityFiguresOf(rep);
        k->mesh_seconds = rep.mesh_seconds;
        // Hierarchical: links instead of form factors, and the solver's whole memory.
        const bool links = rep.cluster_links + rep.side_links > 0;
        log->info(
            "job={} radiosity: {} patches, {} unknowns, {}, residual {:.2e}, {} {:.2f} s ({} "
            "MiB), solve {:.2f} s",
            job_id, rep.patches, rep.sides, Plural(rep.iterations, "iteration"), rep.residual,
            links ? "links" : "form factors", rep.form_factor_seconds,
            (links ? rep.solver_bytes : rep.form_factor_bytes) >> 20, rep.solve_seconds);
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
            MakeRayTracer(method, *k->embree, options.max_depth, options.render.light_strategy);
        if (!tracer.ok()) return tracer.status();
        k->estimator = std::move(*tracer);
    }
    return k;
}

// The settings a render uses, logged once for a still or a whole shot.
void LogRenderSettings(const LocalRenderOptions& options, const Scene& scene, Method method,
                       const std::optional<SplatPlanSettings>& splat_plan,
                       const std::string& job_id) {
    auto log = NamedLogger("render");
    const MethodInfo& info = Info(method);
    if (method == Method::kWhitted) {
        for (const std::string& term : WhittedMissingTerms(scene)) {
            log->info("job={} whitted leaves out {}", job_id, term);
        }
    }
    log->info(
        "job={} rendering {} ({}x{}, {} spp, {} sampler{}, seed {}, max depth {}, tile {}, {} "
        "filter{}{})",
        job_id, options.scene_path, scene.camera.width, scene.camera.height, options.render.spp,
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
        options.render.tile, DescribePixelFilter(scene.camera.filter),
        options.render.clamp > 0 ? absl::StrCat(", clamp ", options.render.clamp, " (biased)")
                                 : std::string(),
        options.render.aovs != 0 ? ", AOVs " + AovListName(options.render.aovs) : std::string());
    log->info("job={} camera: {}", job_id, DescribeCamera(scene.camera));
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
    if (IsAdaptive(options)) {
        log->info(
            "job={} adaptive: first pass {} spp, target error {}, noise threshold {}, time limit "
            "{} "
            "s, at most {} spp",
            job_id, options.render.spp, options.adaptive.target_error,
            options.adaptive.noise_threshold, options.adaptive.time_limit,
            options.adaptive.max_spp);
    }
}

// Samples the image of `job` (a still, or one frame of a shot) with `k` and writes its files;
// fills the sampling's part of `summary`, its total from `start`.
absl::Status RenderAndWrite(const PosedKernels& k, const LocalRenderOptions& options,
                            const JobSpec& job, const std::optional<SplatPlanSettings>& splat_plan,
                            const std::string& exr_path, const std::string& png_path,
                            const std::string& false_color_path, absl::Time start,
                            LocalRenderSummary& summary) {
    auto log = NamedLogger("render");
    const std::string& job_id = summary.job_id;
    const bool adaptive = IsAdaptive(options);
    const Camera& camera = *k.camera;
    if (options.progress) options.progress->Start();
    const ProgressFn progress = [&](size_t done, size_t n) {
        if (options.progress) options.progress->Update(done, n);
    };
    const std::atomic<bool>* interrupt =
        options.interrupt && !k.splat_renderer ? &options.interrupt->requested : nullptr;
    if (interrupt) options.interrupt->honoured = true;
    absl::StatusOr<RenderOutput> out =
        k.splat_renderer
            ? RenderSplatImage(camera, *k.splat_renderer, *splat_plan, options.render, progress)
        : adaptive ? RenderImageAdaptive(camera, *k.estimator, options.render, options.adaptive,
                                         progress, {}, interrupt)
                   : RenderImage(camera, *k.estimator, options.render, progress, interrupt);
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

    if (out->stats.truncated_paths > 0 && summary.method == Method::kWhitted) {
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
    if (!exr_path.empty()) {
        if (absl::Status s = WriteExr(exr_path, out->image, description->attributes); !s.ok()) {
            return s;
        }
    }
    if (!png_path.empty()) {
        if (absl::Status s = WritePng(png_path, out->image, options.preview); !s.ok()) return s;
    }
    if (options.false_color) {
        if (absl::Status s = WriteFalseColorPng(false_color_path, out->image, *options.false_color);
            !s.ok()) {
            return s;
        }
    }
    return absl::OkStatus();
}

// The loaded scene, its job and its method: what a still and every frame of a shot share.
struct LoadedRender {
    Scene scene;
    std::string job_id;
    Method method = Method::kPath;
    JobSpec job;
    std::optional<SplatPlanSettings> splat_plan;
};

absl::StatusOr<LoadedRender> LoadRender(const LocalRenderOptions& options) {
    auto log = NamedLogger("render");
    if (options.false_color) {
        if (absl::Status s = CheckFalseColorSource(*options.false_color, options.render.aovs);
            !s.ok()) {
            return s;
        }
    }
    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    LoadedRender r{.scene = std::move(*scene)};
    r.job_id = "local-" + r.scene.content_hash.substr(0, 8);
    const MethodChoice choice = ChooseMethod(r.scene, options.method);
    r.method = choice.method;
    // What the farm refuses at submission (media a method does not render, say) is refused here.
    if (absl::Status s = CheckMethodTakesScene(r.method, r.scene); !s.ok()) return s;
    PrepareSceneFor(r.method, r.scene);
    const MethodInfo& info = Info(r.method);
    log->info("job={} method {} ({})", r.job_id, info.name, choice.why);
    r.job = LocalJobOf(options, r.scene, info);
    absl::StatusOr<std::optional<SplatPlanSettings>> plan = SplatPlanOf(options, r.job, info);
    if (!plan.ok()) return plan.status();
    r.splat_plan = *plan;
    return r;
}

void TakeKernelFigures(const PosedKernels& k, LocalRenderSummary& summary) {
    summary.radiosity_seconds = k.radiosity_seconds;
    summary.radiosity = k.radiosity;
    summary.mesh_seconds = k.mesh_seconds;
}

}  // namespace

namespace {

// Radiosity's files name one solve. Frames of a scene that moves solve anew each, so one file
// would be overwritten (--save-solution, --export-ply) or applied to geometry it does not fit
// (--load-solution: its check compares counts and the scene's hash, which motion keeps).
absl::Status CheckSolutionFilesOfShot(const LocalRenderOptions& options, const Scene& scene,
                                      const FrameRange& frames) {
    if (frames.count() == 1 || !scene.animation || !scene.animation->Moves()) {
        return absl::OkStatus();
    }
    for (const auto& [flag, path] : {std::pair{"--save-solution", &options.save_solution},
                                     std::pair{"--load-solution", &options.load_solution},
                                     std::pair{"--export-ply", &options.export_ply}}) {
        if (path->empty()) continue;
        return absl::InvalidArgumentError(absl::StrCat(
            flag, " ", *path, " with --frames ", FrameRangeText(frames), ": ", scene.source,
            " moves, so each frame solves anew and one file cannot hold them; use --frame N"));
    }
    return absl::OkStatus();
}

}  // namespace

absl::Status CheckShotOutputs(const LocalRenderOptions& options, const FrameRange& frames) {
    // -o names the EXR, or the PNG when there is no EXR; --png the PNG beside an EXR.
    if (!options.exr_path.empty()) {
        if (absl::Status s = CheckFramePattern("-o", options.exr_path, frames); !s.ok()) return s;
    }
    if (options.png_path.empty()) return absl::OkStatus();
    return CheckFramePattern(options.exr_path.empty() ? "-o" : "--png", options.png_path, frames);
}

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options) {
    const absl::Time start = absl::Now();
    absl::StatusOr<LoadedRender> r = LoadRender(options);
    if (!r.ok()) return r.status();
    absl::StatusOr<std::unique_ptr<PosedKernels>> k =
        BuildKernels(r->scene, options, r->method, r->job, r->job_id);
    if (!k.ok()) return k.status();
    LocalRenderSummary summary;
    summary.job_id = r->job_id;
    summary.method = r->method;
    summary.load_seconds = absl::ToDoubleSeconds(absl::Now() - start) - (*k)->radiosity_seconds;
    TakeKernelFigures(**k, summary);
    LogRenderSettings(options, r->scene, r->method, r->splat_plan, r->job_id);
    if (absl::Status s = RenderAndWrite(**k, options, r->job, r->splat_plan, options.exr_path,
                                        options.png_path, options.false_color_path, start, summary);
        !s.ok()) {
        return s;
    }
    return summary;
}

absl::StatusOr<LocalShotSummary> RunLocalShot(const LocalRenderOptions& options,
                                              const ShotSettings& shot) {
    auto log = NamedLogger("render");
    const absl::Time start = absl::Now();
    if (!shot.frames) return absl::InvalidArgumentError("a shot needs --frames or --frame");
    if (absl::Status s = CheckShotSettings(shot); !s.ok()) return s;
    const FrameRange& frames = *shot.frames;
    if (absl::Status s = CheckShotOutputs(options, frames); !s.ok()) return s;
    absl::StatusOr<LoadedRender> r = LoadRender(options);
    if (!r.ok()) return r.status();
    r->job.shot = shot;
    if (absl::Status s = CheckShutterOfMethod(r->method, shot.shutter); !s.ok()) return s;
    if (absl::Status s = CheckSolutionFilesOfShot(options, r->scene, frames); !s.ok()) return s;
    // A malformed animation fails the first frame's pose, before any file is written.
    const bool moves = r->scene.animation && r->scene.animation->Moves();
    LocalShotSummary shot_summary;
    shot_summary.job_id = r->job_id;
    shot_summary.moves = moves;
    std::unique_ptr<PosedKernels> kernels;
    for (int i = 0; i < frames.count(); ++i) {
        const int frame = frames.at(i);
        const absl::Time frame_start = absl::Now();
        LocalFrameSummary f;
        f.frame = frame;
        f.time = FrameSeconds(frame, shot.fps);
        f.exr_path = options.exr_path.empty() ? "" : FramePath(options.exr_path, frame);
        f.png_path = options.png_path.empty() ? "" : FramePath(options.png_path, frame);
        if (absl::Status s = PoseSceneAtFrame(frame, shot, r->scene); !s.ok()) return s;
        f.pose_seconds = absl::ToDoubleSeconds(absl::Now() - frame_start);
        // A scene that does not move renders every frame on the first frame's kernels.
        if (!kernels || moves) {
            kernels.reset();  // one BVH in memory at a time
            const ShutterInterval shutter = ShutterOf(frame, shot);
            absl::StatusOr<std::unique_ptr<PosedKernels>> k =
                BuildKernels(r->scene, options, r->method, r->job, r->job_id,
                             {r->scene.animation.get(), shutter.open, shutter.close});
            if (!k.ok()) return k.status();
            kernels = std::move(*k);
            f.bvh_seconds = kernels->bvh_seconds;
            if (i == 0) LogRenderSettings(options, r->scene, r->method, r->splat_plan, r->job_id);
        }
        LocalRenderSummary& summary = f.render;
        summary.job_id = r->job_id;
        summary.method = r->method;
        summary.load_seconds = f.pose_seconds + f.bvh_seconds;
        TakeKernelFigures(*kernels, summary);
        if (options.progress) options.progress->StartFrame(i, frames.count(), frame);
        if (absl::Status s = RenderAndWrite(
                *kernels, options, FrameSpec(r->job, frame), r->splat_plan, f.exr_path, f.png_path,
                options.false_color ? FramePath(options.false_color_path, frame) : std::string(),
                frame_start, summary);
            !s.ok()) {
            return s;
        }
        log->info(
            "job={} frame {} ({:.4f} s): pose {:.3f} ms, BVH {}, render {:.2f} s, total {:.2f} "
            "s{}",
            r->job_id, frame, f.time, 1e3 * f.pose_seconds,
            f.bvh_seconds > 0 ? absl::StrFormat("%.1f ms", 1e3 * f.bvh_seconds)
                              : std::string("reused"),
            summary.render_seconds, summary.seconds, summary.partial.empty() ? "" : " (partial)");
        const bool stop = !summary.partial.empty();
        shot_summary.frames.push_back(std::move(f));
        if (options.progress) options.progress->FinishFrame(i + 1, frames.count());
        if (stop) {
            shot_summary.partial = absl::StrCat(
                "frame ", frame, " ", shot_summary.frames.back().render.partial,
                "; the shot stopped after ", Plural(i + 1, "frame"), " of ", frames.count());
            log->warn("job={} {}", r->job_id, shot_summary.partial);
            break;
        }
    }
    shot_summary.seconds = absl::ToDoubleSeconds(absl::Now() - start);
    return shot_summary;
}

}  // namespace lf
