#include "local_executor.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>

#include "lf/core/image_error.h"
#include "lf/kernels/tile_renderer.h"
#include "server/adaptive_plan.h"
#include "server/merge.h"
#include "server/plan.h"

namespace lf {

absl::StatusOr<RenderOutput> RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                                         const RenderSettings& settings,
                                         const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    absl::StatusOr<std::vector<RenderTask>> tasks =
        PlanRender({camera.width(), camera.height(), settings.spp, settings.tile, settings.passes});
    if (!tasks.ok()) return tasks.status();
    RenderMerger merger(camera.width(), camera.height(), *tasks);
    std::mutex mutex;
    absl::Status status;
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, tasks->size(), 1),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t i = range.begin(); i != range.end(); ++i) {
                    const RenderTask& task = (*tasks)[i];
                    const TileSums sums = RenderTile(camera, estimator, task.rect, settings.seed,
                                                     task.sample_begin, task.sample_end);
                    std::lock_guard<std::mutex> lock(mutex);
                    status.Update(merger.Add(task.index, sums));
                    if (progress) progress(merger.tasks_done(), merger.task_count());
                }
            },
            tbb::simple_partitioner());
    });
    if (!status.ok()) return status;
    RenderOutput out{merger.Snapshot(), merger.stats(), 0, {}};
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

absl::StatusOr<RenderOutput> RenderImageAdaptive(const Camera& camera,
                                                 const RadianceEstimator& estimator,
                                                 const RenderSettings& settings,
                                                 const AdaptiveSettings& adaptive,
                                                 const ProgressFn& progress) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> made = AdaptiveTilePlan::Make(
        camera.width(), camera.height(), settings.spp, settings.tile, adaptive);
    if (!made.ok()) return made.status();
    AdaptiveTilePlan& plan = **made;

    RenderOutput out;
    std::mutex mutex;
    absl::Status status;
    size_t tiles_done = 0;
    bool shortened = false;
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    // Rounds of one pass for every unfinished tile, so that a time limit leaves the tiles
    // evenly sampled rather than the first ones finished and the rest at their first pass.
    std::vector<RenderTask> round = plan.tasks();
    const size_t tiles = round.size();
    while (!round.empty()) {
        if (adaptive.time_limit > 0 && out.stats.samples > 0) {
            const double left = adaptive.time_limit - elapsed();
            if (left <= 0) {
                plan.Stop();
                break;
            }
            uint64_t planned = 0;
            for (const RenderTask& task : round) {
                planned += (task.sample_end - task.sample_begin) * uint64_t(task.rect.Area());
            }
            const double affordable = left / (elapsed() / double(out.stats.samples));
            if (double(planned) > affordable) {
                shortened = true;
                const double scale = affordable / double(planned);
                for (RenderTask& task : round) {
                    plan.Shorten(task.index,
                                 task.sample_begin +
                                     uint64_t(double(task.sample_end - task.sample_begin) * scale));
                    task = plan.tasks()[size_t(task.index)];
                }
            }
        }
        std::vector<RenderTask> next;
        arena.execute([&] {
            tbb::parallel_for(
                tbb::blocked_range<size_t>(0, round.size(), 1),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t k = range.begin(); k != range.end(); ++k) {
                        const RenderTask& task = round[k];
                        const TileSums sums =
                            RenderTile(camera, estimator, task.rect, settings.seed,
                                       task.sample_begin, task.sample_end);
                        std::lock_guard<std::mutex> lock(mutex);
                        absl::StatusOr<std::optional<RenderTask>> pass =
                            plan.Merge(task.index, sums);
                        if (!pass.ok()) {
                            status.Update(pass.status());
                        } else if (*pass) {
                            next.push_back(**pass);
                        } else if (progress) {
                            progress(++tiles_done, tiles);
                        }
                    }
                },
                tbb::simple_partitioner());
        });
        if (!status.ok()) return status;
        out.stats = plan.stats();
        round = std::move(next);
    }
    out.image = plan.Snapshot();
    absl::StatusOr<AdaptiveReport> report = plan.Report();
    if (!report.ok()) return report.status();
    out.adaptive = std::move(*report);
    out.adaptive.timed_out |= shortened;
    out.seconds = elapsed();
    return out;
}

}  // namespace lf
