#include "lf/local/local_executor.h"

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "lf/core/cancel.h"
#include "lf/job/adaptive_tile_execution.h"
#include "lf/job/splat_execution.h"
#include "lf/job/tile_execution.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/execution_runner.h"

namespace lf {

namespace {

// Where a local render keeps its tiles' exact sums (104 bytes a pixel, about twice that with
// AOVs): in memory for images up to 2048x2048 (1448x1448 with AOVs, the same memory), in an
// unlinked temporary file above, as the farm does, so that a large render's peak memory is its
// float image (40 bytes a pixel, 68 with every AOV) rather than the sums of every tile.
TileStoreFactory TileStoreFor(const Camera& camera, uint32_t aovs) {
    const int64_t in_memory_pixels = int64_t(2048) * 2048 / (aovs != 0 ? 2 : 1);
    if (int64_t(camera.width()) * camera.height() <= in_memory_pixels) return MakeMemoryTileStore;
    return [](std::vector<PixelRect> tiles, uint32_t aovs) {
        return MakeFileTileStore(std::filesystem::temp_directory_path().string(), std::move(tiles),
                                 aovs);
    };
}

SampleOptions SampleOptionsOf(const RenderSettings& settings) {
    return {settings.clamp, settings.aovs, settings.sampler};
}

// Runs a tile execution's tasks with lf::RenderTile.
absl::Status RunTiles(TileExecution& execution, const Camera& camera,
                      const RadianceEstimator& estimator, const RenderSettings& settings,
                      RunOptions options, absl::Time started) {
    options.threads = settings.threads;
    return RunExecution(
        execution,
        [&](const TaskAssignment& lease, const std::atomic<bool>& cancel, const auto& merge) {
            const RenderTask& task = lease.task;
            const PixelMask active = task.active();
            const TileSums sums =
                RenderTile(camera, estimator, task.rect, settings.seed, task.sample_begin,
                           task.sample_end, SampleOptionsOf(settings), &cancel, &active);
            return merge(TaskResult{.sums = &sums});
        },
        options, started);
}

// The image of an execution, complete or interrupted, its stats, and the seconds since
// `started`.
absl::StatusOr<RenderOutput> Output(const JobExecution& execution, const RunClock& clock,
                                    absl::Time started, const std::atomic<bool>* interrupt) {
    absl::StatusOr<Image> image = execution.SnapshotReader()();
    if (!image.ok()) return image.status();
    RenderOutput out{std::move(*image), execution.stats(), 0, {}};
    out.seconds = absl::ToDoubleSeconds(clock() - started);
    out.tasks_done = execution.tasks_done();
    out.task_count = execution.task_count();
    out.interrupted = CancelRequested(interrupt) && out.tasks_done < out.task_count;
    return out;
}

RunClock ClockOr(const RunClock& clock) {
    return clock ? clock : [] { return absl::Now(); };
}

}  // namespace

absl::StatusOr<RenderOutput> RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                                         const RenderSettings& settings, const ProgressFn& progress,
                                         const std::atomic<bool>* interrupt) {
    const RunClock clock = ClockOr({});
    const absl::Time started = clock();
    absl::StatusOr<std::unique_ptr<TileExecution>> made = TileExecution::Make(
        {camera.width(), camera.height(), settings.spp, settings.tile, settings.passes},
        TileStoreFor(camera, settings.aovs), settings.aovs);
    if (!made.ok()) return made.status();
    TileExecution& execution = **made;
    RunOptions options;
    options.merged = [&] {
        if (progress) progress(execution.tasks_done(), execution.task_count());
    };
    options.interrupt = interrupt;
    if (absl::Status s = RunTiles(execution, camera, estimator, settings, options, started);
        !s.ok()) {
        return s;
    }
    return Output(execution, clock, started, interrupt);
}

absl::StatusOr<RenderOutput> RenderSplatImage(const Camera& camera, const SplatRenderer& renderer,
                                              const SplatPlanSettings& plan,
                                              const RenderSettings& settings,
                                              const ProgressFn& progress) {
    const RunClock clock = ClockOr({});
    const absl::Time started = clock();
    if (plan.width != camera.width() || plan.height != camera.height()) {
        return absl::InvalidArgumentError(absl::StrCat("splat plan ", plan.width, "x", plan.height,
                                                       " is not the camera's ", camera.width(), "x",
                                                       camera.height()));
    }
    // Two stores (camera sums, splat sums), each as a tile render's, in a file above 2048x2048.
    absl::StatusOr<std::unique_ptr<SplatExecution>> made =
        SplatExecution::Make(plan, TileStoreFor(camera, 0));
    if (!made.ok()) return made.status();
    SplatExecution& execution = **made;
    RunOptions options;
    options.threads = settings.threads;
    options.merged = [&] {
        if (progress) progress(execution.tasks_done(), execution.task_count());
    };
    const absl::Status status = RunExecution(
        execution,
        [&](const TaskAssignment& lease, const std::atomic<bool>&, const auto& merge) {
            const RenderTask& task = lease.task;
            TileSums camera_sums(task.rect, 0);
            SplatList splats(plan.width, plan.height);
            renderer.Render(
                {task.rect, task.sample_begin, task.sample_end, lease.path_begin, lease.path_end},
                camera_sums, splats);
            return merge(TaskResult{.sums = &camera_sums, .splats = &splats});
        },
        options, started);
    if (!status.ok()) return status;
    return Output(execution, clock, started, nullptr);
}

absl::StatusOr<RenderOutput> RenderImageAdaptive(
    const Camera& camera, const RadianceEstimator& estimator, const RenderSettings& settings,
    const AdaptiveSettings& adaptive, const ProgressFn& progress, const RunClock& run_clock,
    const std::atomic<bool>* interrupt) {
    const RunClock clock = ClockOr(run_clock);
    const absl::Time started = clock();
    absl::StatusOr<std::unique_ptr<AdaptiveTileExecution>> made = AdaptiveTileExecution::Make(
        camera.width(), camera.height(), settings.spp, settings.tile, adaptive, kMaxTaskSamples,
        TileStoreFor(camera, settings.aovs), settings.aovs);
    if (!made.ok()) return made.status();
    AdaptiveTileExecution& execution = **made;
    RunOptions options;
    options.clock = clock;
    options.merged = [&] {
        if (progress) progress(execution.tiles_finished(), execution.tile_count());
    };
    options.interrupt = interrupt;
    if (absl::Status s = RunTiles(execution, camera, estimator, settings, options, started);
        !s.ok()) {
        return s;
    }
    absl::StatusOr<RenderOutput> out = Output(execution, clock, started, interrupt);
    if (!out.ok()) return out.status();
    absl::StatusOr<AdaptiveReport> report = execution.Report();
    if (!report.ok()) return report.status();
    out->adaptive = std::move(*report);
    return out;
}

}  // namespace lf
