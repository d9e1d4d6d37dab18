#include "local_executor.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <mutex>

#include "lf/kernels/tile_renderer.h"
#include "server/merge.h"
#include "server/plan.h"

namespace lf {

absl::StatusOr<RenderOutput> RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                                         const RenderSettings& settings,
                                         const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    absl::StatusOr<std::vector<RenderTask>> tasks = PlanRender(
        {camera.width(), camera.height(), settings.spp, settings.tile, settings.passes});
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
    RenderOutput out{merger.Snapshot(), merger.stats(), 0};
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace lf
