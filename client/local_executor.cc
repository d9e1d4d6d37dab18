#include "local_executor.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>

#include "lf/core/image_error.h"
#include "lf/kernels/tile_renderer.h"
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

namespace {

uint64_t RoundUpToEven(uint64_t n) { return n + (n & 1); }

// The next sample count of a tile at `error` after `n` samples: the error of a mean falls as
// 1/sqrt(n), so n (error / target)^2 is the prediction, plus 10 % so that a prediction a little
// low does not cost a whole extra pass; at most 8x per pass, so one noisy estimate cannot ask
// for far too much.
uint64_t NextSampleCount(uint64_t n, double error, double target, uint64_t max_spp) {
    const double predicted = double(n) * (error / target) * (error / target) * 1.1;
    const double next = std::clamp(predicted, double(n + 2), double(n) * 8);
    return std::min(max_spp, RoundUpToEven(uint64_t(std::ceil(next))));
}

}  // namespace

absl::StatusOr<RenderOutput> RenderImageAdaptive(const Camera& camera,
                                                 const RadianceEstimator& estimator,
                                                 const RenderSettings& settings,
                                                 const AdaptiveSettings& adaptive,
                                                 const ProgressFn& progress) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    const uint64_t max_spp = RoundUpToEven(std::max<uint64_t>(adaptive.max_spp, 2));
    const uint64_t first = std::min(max_spp, RoundUpToEven(std::max<uint64_t>(settings.spp, 2)));
    // The planner's tiles, one pass each: only their rectangles are used.
    absl::StatusOr<std::vector<RenderTask>> plan =
        PlanRender({camera.width(), camera.height(), first, settings.tile, 1});
    if (!plan.ok()) return plan.status();

    struct Tile {
        TileSums sums;
        uint64_t next;  // sample count after the coming pass
        double error = 1;
        bool done = false;
    };
    std::vector<Tile> tiles;
    for (const RenderTask& task : *plan) tiles.push_back({TileSums(task.rect), first});

    RenderOutput out;
    std::mutex mutex;
    size_t tiles_done = 0;
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    // Rounds of one pass for every unfinished tile, so that a time limit leaves the tiles
    // evenly sampled rather than the first ones finished and the rest at their first pass.
    for (int round = 0;; ++round) {
        std::vector<size_t> active;
        uint64_t planned = 0;
        for (size_t i = 0; i < tiles.size(); ++i) {
            if (tiles[i].done) continue;
            active.push_back(i);
            planned += (tiles[i].next - tiles[i].sums.pixels[0].Count()) *
                       uint64_t(tiles[i].sums.rect.Area());
        }
        if (active.empty()) break;
        if (round > 0 && adaptive.time_limit > 0) {
            const double left = adaptive.time_limit - elapsed();
            const double seconds_per_sample = elapsed() / double(out.stats.samples);
            if (left <= 0) {
                out.adaptive.timed_out = true;
                break;
            }
            const double affordable = left / seconds_per_sample;
            if (double(planned) > affordable) {
                out.adaptive.timed_out = true;
                const double scale = affordable / double(planned);
                for (size_t i : active) {
                    const uint64_t n = tiles[i].sums.pixels[0].Count();
                    tiles[i].next = n + RoundUpToEven(std::max<uint64_t>(
                                            1, uint64_t(double(tiles[i].next - n) * scale)));
                }
            }
        }
        arena.execute([&] {
            tbb::parallel_for(
                tbb::blocked_range<size_t>(0, active.size(), 1),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t k = range.begin(); k != range.end(); ++k) {
                        Tile& tile = tiles[active[k]];
                        const uint64_t n = tile.sums.pixels[0].Count();
                        tile.sums += RenderTile(camera, estimator, tile.sums.rect, settings.seed, n,
                                                tile.next);
                        tile.error = EstimatedRelativeError(tile.sums);
                        const bool reached =
                            adaptive.target_error > 0 && tile.error <= adaptive.target_error;
                        tile.done = reached || tile.next >= max_spp;
                        tile.next = adaptive.target_error > 0
                                        ? NextSampleCount(tile.next, tile.error,
                                                          adaptive.target_error, max_spp)
                                        : std::min(max_spp, 2 * tile.next);
                        std::lock_guard<std::mutex> lock(mutex);
                        if (tile.done) {
                            ++tiles_done;
                            if (progress) progress(tiles_done, tiles.size());
                        }
                    }
                },
                tbb::simple_partitioner());
        });
        out.stats = RenderStats();
        for (const Tile& tile : tiles) out.stats += tile.sums.stats;
    }

    out.image = Image(camera.width(), camera.height());
    AdaptiveReport& report = out.adaptive;
    report.tiles = int(tiles.size());
    report.min_spp = max_spp;
    for (const Tile& tile : tiles) {
        out.image.SetTile(tile.sums);
        const uint64_t n = tile.sums.pixels[0].Count();
        report.worst_tile_error = std::max(report.worst_tile_error, tile.error);
        if (adaptive.target_error > 0 && tile.error > adaptive.target_error) {
            ++report.tiles_above_target;
        }
        report.min_spp = std::min(report.min_spp, n);
        report.max_spp = std::max(report.max_spp, n);
        report.per_tile.push_back({tile.sums.rect, n, tile.error});
    }
    absl::StatusOr<double> estimated = EstimatedRelativeError(out.image);
    if (!estimated.ok()) return estimated.status();
    report.estimated_error = *estimated;
    out.seconds = elapsed();
    return out;
}

}  // namespace lf
