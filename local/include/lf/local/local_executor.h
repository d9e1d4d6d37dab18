// The in-process executor of local mode: the farm's job executions (lf/job/job_execution.h: its
// plans and mergers) run on TBB threads (lf/local/execution_runner.h), each task rendered with
// lf::RenderTile or the frame renderer as a worker would. So `lightfarm render` and a farm render
// of the same job are the same code and the same bits.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/camera.h"
#include "lf/core/image.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/settings.h"
#include "lf/job/splat_plan.h"
#include "lf/kernels/radiance.h"
#include "lf/kernels/splat_renderer.h"
#include "lf/local/execution_runner.h"

namespace lf {

struct RenderSettings {
    uint64_t spp = defaults::kSpp;
    uint64_t seed = defaults::kSeed;
    int threads = 0;  // 0: all cores
    int tile = defaults::kTile;
    int passes = defaults::kPasses;  // sample passes per tile, as on the farm
    // `--clamp`: above 0, a sample whose radiance exceeds it in some channel is scaled down
    // so that channel equals it (biased: it removes fireflies and energy with them).
    double clamp = 0;
    uint32_t aovs = 0;                         // lf/core/aov.h flags: first-hit AOV channels to add
    SamplerType sampler = defaults::kSampler;  // `--sampler`
    // `--light-sampling`: RenderImage takes an estimator already built, so this is for the
    // caller that builds it (PathTracer(scene, max_depth, light_strategy)), as local mode does.
    LightStrategy light_strategy = defaults::kLightStrategy;
};

struct RenderOutput {
    Image image;  // R,G,B, A.*, B.*, spp
    RenderStats stats;
    double seconds = 0;
    AdaptiveReport adaptive;  // RenderImageAdaptive only
    // Stopped by `interrupt`: the image holds the tasks (whole passes of tiles) merged before,
    // tasks_done of task_count, each pixel the mean of its own samples (spp; 0 where none ran).
    bool interrupted = false;
    size_t tasks_done = 0, task_count = 0;
};

// Called from worker threads with (tasks done, tasks in all); must be thread-safe.
using ProgressFn = std::function<void(size_t, size_t)>;

// `interrupt` (RunOptions::interrupt) stops it with the passes merged so far.
absl::StatusOr<RenderOutput> RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                                         const RenderSettings& settings,
                                         const ProgressFn& progress = {},
                                         const std::atomic<bool>* interrupt = nullptr);

// Adaptive sampling (lf::AdaptiveTileExecution) on settings.threads threads, each taking the
// least sampled tile's pass next; at the time limit, read from `clock` (empty: absl::Now), the
// passes under way are cut and dropped, as on the farm. settings.spp is the first pass of every
// tile (rounded up to even, so A and B are equal halves); settings.passes is ignored. Progress
// counts finished tiles. `interrupt` stops it as RenderImage's does.
absl::StatusOr<RenderOutput> RenderImageAdaptive(
    const Camera& camera, const RadianceEstimator& estimator, const RenderSettings& settings,
    const AdaptiveSettings& adaptive, const ProgressFn& progress = {}, const RunClock& clock = {},
    const std::atomic<bool>* interrupt = nullptr);

// A splatting method's render (light tracing, BDPT, photon mapping): PlanSplatRender cuts it into
// splat tasks, settings.threads threads run them with `renderer` as a worker would (each task in
// the same arena, the renderer free to parallel_for inside it), and SplatMerger adds their
// camera sums and splat lists into the image, so the bits are the farm's for the same plan.
// `plan` comes from SplatPlanSettingsOf (lf/job/splat_settings.h); of `settings` only threads is
// used (the rest is the renderer's). Progress counts tasks.
absl::StatusOr<RenderOutput> RenderSplatImage(const Camera& camera, const SplatRenderer& renderer,
                                              const SplatPlanSettings& plan,
                                              const RenderSettings& settings,
                                              const ProgressFn& progress = {});

}  // namespace lf
