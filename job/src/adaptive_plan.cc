#include "lf/job/adaptive_plan.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "lf/core/image_error.h"

namespace lf {

namespace {
uint64_t RoundUpToEven(uint64_t n) { return n + (n & 1); }
}  // namespace

absl::Status CheckAdaptiveSettings(const AdaptiveSettings& a) {
    if (!std::isfinite(a.target_error) || a.target_error < 0 || a.target_error > 1) {
        return absl::InvalidArgumentError(
            absl::StrCat("target error ", a.target_error, ": expected 0 (none) or up to 1"));
    }
    if (!std::isfinite(a.time_limit) || a.time_limit < 0) {
        return absl::InvalidArgumentError(
            absl::StrCat("time limit ", a.time_limit, " s: expected 0 (none) or more"));
    }
    if (a.max_spp < 2 || a.max_spp > kMaxSpp) {
        return absl::InvalidArgumentError(
            absl::StrCat("most samples per pixel ", a.max_spp, ": expected 2 to ", kMaxSpp));
    }
    return absl::OkStatus();
}

uint64_t NextSampleCount(uint64_t n, double error, double target, uint64_t max_spp) {
    const double predicted = double(n) * (error / target) * (error / target) * 1.1;
    const double next = std::clamp(predicted, double(n + 2), double(n) * 8);
    return std::min(max_spp, RoundUpToEven(uint64_t(std::ceil(next))));
}

AdaptiveTilePlan::AdaptiveTilePlan(int width, int height, const AdaptiveSettings& settings,
                                   uint64_t max_task_samples, std::shared_ptr<TileStore> store)
    : TileMerger(width, height, std::move(store)),
      settings_(settings),
      max_task_samples_(std::max<uint64_t>(max_task_samples, 1)) {
    settings_.max_spp = RoundUpToEven(settings.max_spp);
}

absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> AdaptiveTilePlan::Make(
    int width, int height, uint64_t first_spp, int tile, const AdaptiveSettings& settings,
    uint64_t max_task_samples, const TileStoreFactory& make_store, uint32_t aovs) {
    if (absl::Status s = CheckAdaptiveSettings(settings); !s.ok()) return s;
    const uint64_t first =
        std::min(RoundUpToEven(settings.max_spp), RoundUpToEven(std::max<uint64_t>(first_spp, 2)));
    absl::StatusOr<std::vector<RenderTask>> tiles = PlanRender({width, height, first, tile, 1});
    if (!tiles.ok()) return tiles.status();
    absl::StatusOr<std::unique_ptr<TileStore>> store = make_store(TileRects(*tiles), aovs);
    if (!store.ok()) return store.status();
    std::unique_ptr<AdaptiveTilePlan> plan(
        new AdaptiveTilePlan(width, height, settings, max_task_samples, std::move(*store)));
    plan->first_ = first;
    for (const RenderTask& task : *tiles) plan->tiles_.push_back({task.rect, 0, 1, {}});
    for (int t = 0; t < int(plan->tiles_.size()); ++t) plan->AppendPass(t, 0, plan->first_);
    return plan;
}

std::vector<RenderTask> AdaptiveTilePlan::AppendPass(int t, uint64_t begin, uint64_t end) {
    Tile& tile = tiles_[size_t(t)];
    const uint64_t pairs = (end - begin) / 2;
    const uint64_t samples = (end - begin) * uint64_t(tile.rect.Area());
    const uint64_t parts = std::min(pairs, (samples + max_task_samples_ - 1) / max_task_samples_);
    std::vector<RenderTask> appended;
    for (uint64_t i = 0; i < parts; ++i) {
        const RenderTask task{int(tasks_.size()), tile.rect, begin + 2 * (pairs * i / parts),
                              begin + 2 * (pairs * (i + 1) / parts)};
        tasks_.push_back(task);
        tile_of_.push_back(t);
        merged_.push_back(false);
        dropped_.push_back(false);
        tile.pending.push_back(task.index);
        appended.push_back(task);
    }
    return appended;
}

bool AdaptiveTilePlan::IsPending(int t) const {
    return t >= 0 && size_t(t) < tasks_.size() && !merged_[size_t(t)] && !dropped_[size_t(t)];
}

absl::StatusOr<std::vector<RenderTask>> AdaptiveTilePlan::Merge(int t, const TileSums& sums) {
    if (t >= 0 && size_t(t) < tasks_.size() && merged_[size_t(t)]) {
        return absl::AlreadyExistsError(absl::StrCat("task ", t, " is already merged"));
    }
    if (!IsPending(t)) {
        return absl::InvalidArgumentError(
            absl::StrCat("task ", t, " is not a pass planned and still wanted"));
    }
    if (absl::Status s = CheckTaskResult(tasks_[size_t(t)], sums); !s.ok()) return s;
    const int tile_index = tile_of_[size_t(t)];
    const absl::StatusOr<TileSums> merged = AddToTile(tile_index, sums);
    if (!merged.ok()) return merged.status();
    merged_[size_t(t)] = true;
    ++tasks_done_;
    stats_ += sums.stats;
    Tile& tile = tiles_[size_t(tile_index)];
    tile.spp = merged->pixels[0].Count();
    tile.error = EstimatedTileError(*merged);
    std::erase(tile.pending, t);
    // The pass's other tasks are still out: the tile decides on the whole pass.
    if (!tile.pending.empty()) return std::vector<RenderTask>();
    const uint64_t n = tile.spp;
    const bool reached = settings_.target_error > 0 && tile.error <= settings_.target_error;
    if (reached || n >= settings_.max_spp || stopped_) return std::vector<RenderTask>();
    const uint64_t next =
        settings_.target_error > 0
            ? NextSampleCount(n, tile.error, settings_.target_error, settings_.max_spp)
            : std::min(settings_.max_spp, 2 * n);
    return AppendPass(tile_index, n, next);
}

bool AdaptiveTilePlan::Complete() const { return tiles_finished() == tiles_.size(); }

size_t AdaptiveTilePlan::tiles_finished() const {
    return size_t(std::count_if(tiles_.begin(), tiles_.end(),
                                [](const Tile& t) { return t.pending.empty(); }));
}

std::vector<int> AdaptiveTilePlan::Stop() {
    stopped_ = true;
    std::vector<int> dropped;
    for (Tile& tile : tiles_) {
        std::erase_if(tile.pending, [&](int t) {
            if (tasks_[size_t(t)].sample_end <= first_) return false;
            dropped_[size_t(t)] = true;
            dropped.push_back(t);
            return true;
        });
    }
    std::sort(dropped.begin(), dropped.end());
    return dropped;
}

absl::StatusOr<AdaptiveReport> AdaptiveTilePlan::Report() const {
    AdaptiveReport report = TileReport();
    absl::StatusOr<Image> snapshot = Snapshot();
    if (!snapshot.ok()) return snapshot.status();
    absl::StatusOr<double> estimated = EstimatedRelativeError(*snapshot);
    if (!estimated.ok()) return estimated.status();
    report.estimated_error = *estimated;
    return report;
}

AdaptiveReport AdaptiveTilePlan::TileReport() const {
    AdaptiveReport report;
    report.tiles = int(tiles_.size());
    report.timed_out = stopped_;
    report.min_spp = settings_.max_spp;
    for (const Tile& tile : tiles_) {
        const uint64_t n = tile.spp;
        report.worst_tile_error = std::max(report.worst_tile_error, tile.error);
        if (settings_.target_error > 0 && tile.error > settings_.target_error) {
            ++report.tiles_above_target;
        }
        report.min_spp = std::min(report.min_spp, n);
        report.max_spp = std::max(report.max_spp, n);
        report.per_tile.push_back({tile.rect, n, tile.error});
    }
    return report;
}

}  // namespace lf
