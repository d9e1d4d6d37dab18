#include "lf/local/local_executor.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <queue>
#include <thread>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "lf/core/image_error.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/frame_merge.h"
#include "lf/job/merge.h"
#include "lf/job/plan.h"
#include "lf/kernels/tile_renderer.h"

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

// Runs tasks 0..count-1 on `threads` threads (0: all cores), each task once: render(i) makes
// its result in parallel, merge(i, result) adds it under one lock (mergers are not
// thread-safe); the first merge error is returned. Exact sums make the order irrelevant.
template <class Render, class Merge>
absl::Status RunTasks(int threads, size_t count, const Render& render, const Merge& merge) {
    std::mutex mutex;
    absl::Status status;
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, count, 1),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t i = range.begin(); i != range.end(); ++i) {
                    auto result = render(i);
                    std::lock_guard<std::mutex> lock(mutex);
                    status.Update(merge(i, result));
                }
            },
            tbb::simple_partitioner());
    });
    return status;
}

// The image the merger holds once every task is in, and the time since `start`.
template <class Merger>
absl::StatusOr<RenderOutput> Finish(const Merger& merger,
                                    std::chrono::steady_clock::time_point start) {
    absl::StatusOr<Image> image = merger.Snapshot();
    if (!image.ok()) return image.status();
    RenderOutput out{std::move(*image), merger.stats(), 0, {}};
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace

absl::StatusOr<RenderOutput> RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                                         const RenderSettings& settings,
                                         const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    absl::StatusOr<std::vector<RenderTask>> tasks =
        PlanRender({camera.width(), camera.height(), settings.spp, settings.tile, settings.passes});
    if (!tasks.ok()) return tasks.status();
    absl::StatusOr<std::unique_ptr<RenderMerger>> made =
        RenderMerger::Make(camera.width(), camera.height(), *tasks,
                           TileStoreFor(camera, settings.aovs), settings.aovs);
    if (!made.ok()) return made.status();
    RenderMerger& merger = **made;
    const absl::Status status = RunTasks(
        settings.threads, tasks->size(),
        [&](size_t i) {
            const RenderTask& task = (*tasks)[i];
            return RenderTile(camera, estimator, task.rect, settings.seed, task.sample_begin,
                              task.sample_end, SampleOptionsOf(settings));
        },
        [&](size_t i, const TileSums& sums) {
            const absl::Status added = merger.Add((*tasks)[i].index, sums);
            if (progress) progress(merger.tasks_done(), merger.task_count());
            return added;
        });
    if (!status.ok()) return status;
    return Finish(merger, start);
}

absl::StatusOr<RenderOutput> RenderFrameImage(const Camera& camera, const FrameRenderer& renderer,
                                              const FramePlanSettings& plan,
                                              const RenderSettings& settings,
                                              const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    if (plan.width != camera.width() || plan.height != camera.height()) {
        return absl::InvalidArgumentError(absl::StrCat("frame plan ", plan.width, "x", plan.height,
                                                       " is not the camera's ", camera.width(), "x",
                                                       camera.height()));
    }
    absl::StatusOr<std::vector<FrameTask>> tasks = PlanFrameRender(plan);
    if (!tasks.ok()) return tasks.status();
    // Two stores (camera sums, splat sums), each as a tile render's, in a file above 2048x2048.
    absl::StatusOr<std::unique_ptr<FrameMerger>> made = FrameMerger::Make(
        plan.width, plan.height, plan.tile, plan.kind, *tasks, TileStoreFor(camera, 0));
    if (!made.ok()) return made.status();
    FrameMerger& merger = **made;
    struct Result {
        TileSums camera;
        SplatList splats;
    };
    const absl::Status status = RunTasks(
        settings.threads, tasks->size(),
        [&](size_t i) {
            const FrameTask& task = (*tasks)[i];
            Result result{TileSums(task.rect, 0), SplatList(plan.width, plan.height)};
            renderer.Render(
                {task.rect, task.sample_begin, task.sample_end, task.path_begin, task.path_end},
                result.camera, result.splats);
            return result;
        },
        [&](size_t i, Result& result) {
            const absl::Status added = merger.Add((*tasks)[i].index, result.camera, result.splats);
            if (progress) progress(merger.tasks_done(), merger.tasks().size());
            return added;
        });
    if (!status.ok()) return status;
    return Finish(merger, start);
}

absl::StatusOr<RenderOutput> RenderImageAdaptive(const Camera& camera,
                                                 const RadianceEstimator& estimator,
                                                 const RenderSettings& settings,
                                                 const AdaptiveSettings& adaptive,
                                                 const ProgressFn& progress) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> made = AdaptiveTilePlan::Make(
        camera.width(), camera.height(), settings.spp, settings.tile, adaptive, kMaxTaskSamples,
        TileStoreFor(camera, settings.aovs), settings.aovs);
    if (!made.ok()) return made.status();
    AdaptiveTilePlan& plan = **made;
    const size_t tiles = plan.tile_count();

    // Passes wait by their first sample, then plan order, as on the farm: every tile's first
    // pass before any second one, and the least sampled tiles first, so a time limit leaves
    // the tiles evenly sampled. No rounds: a tile's next pass starts as soon as its last ends.
    auto later = [](const RenderTask& a, const RenderTask& b) {
        return std::tie(a.sample_begin, a.index) > std::tie(b.sample_begin, b.index);
    };
    std::priority_queue<RenderTask, std::vector<RenderTask>, decltype(later)> queue(later,
                                                                                    plan.tasks());
    std::mutex mutex;
    std::condition_variable changed;
    int running = 0;
    bool finished = false;
    absl::Status status;
    std::atomic<bool> out_of_time{false};  // cancels the passes the time limit drops

    auto work = [&] {
        std::unique_lock<std::mutex> lock(mutex);
        while (true) {
            changed.wait(lock, [&] { return !queue.empty() || running == 0; });
            if (queue.empty() || !status.ok()) break;
            const RenderTask task = queue.top();
            queue.pop();
            if (!plan.IsPending(task.index)) continue;  // dropped by the time limit
            ++running;
            lock.unlock();
            // First passes are never dropped, so never cancelled.
            const bool first = task.sample_end <= plan.first_spp();
            const TileSums sums = RenderTile(
                camera, estimator, task.rect, settings.seed, task.sample_begin, task.sample_end,
                SampleOptionsOf(settings), first ? nullptr : &out_of_time);
            lock.lock();
            --running;
            if (plan.IsPending(task.index)) {  // else cut short: the time limit dropped it
                absl::StatusOr<std::vector<RenderTask>> next = plan.Merge(task.index, sums);
                if (!next.ok()) {
                    status.Update(next.status());
                } else {
                    for (const RenderTask& pass : *next) queue.push(pass);
                    if (progress) progress(plan.tiles_finished(), tiles);
                }
            }
            changed.notify_all();
        }
        finished = true;
        changed.notify_all();
    };
    const int threads = settings.threads > 0
                            ? settings.threads
                            : int(std::max(1u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (int i = 0; i < threads; ++i) pool.emplace_back(work);
    if (adaptive.time_limit > 0) {
        std::unique_lock<std::mutex> lock(mutex);
        const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(adaptive.time_limit));
        if (!changed.wait_until(lock, deadline, [&] { return finished; })) {
            plan.Stop();
            out_of_time = true;
            changed.notify_all();
        }
    }
    for (std::thread& t : pool) t.join();
    if (!status.ok()) return status;

    RenderOutput out;
    out.stats = plan.stats();
    absl::StatusOr<Image> image = plan.Snapshot();
    if (!image.ok()) return image.status();
    out.image = std::move(*image);
    absl::StatusOr<AdaptiveReport> report = plan.Report();
    if (!report.ok()) return report.status();
    out.adaptive = std::move(*report);
    out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return out;
}

}  // namespace lf
