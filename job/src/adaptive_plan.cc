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
    if (!std::isfinite(a.noise_threshold) || a.noise_threshold < 0 || a.noise_threshold > 1) {
        return absl::InvalidArgumentError(absl::StrCat("noise threshold ", a.noise_threshold,
                                                       ": expected 0 (none) or above 0 up to 1"));
    }
    if (a.noise_threshold > 0 && a.target_error > 0) {
        return absl::InvalidArgumentError(
            "a noise threshold (per pixel) and a target error (per tile): pick one");
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

double PixelNoiseError(const PixelSums& pixel) {
    const Rgb a = pixel.HalfMean(0), b = pixel.HalfMean(1);
    double difference = 0, sum = 0;
    for (int c = 0; c < 3; ++c) {
        difference += std::abs(double(b[c]) - double(a[c])) / 2;
        sum += (double(a[c]) + double(b[c])) / 2;
    }
    return difference / (1e-4 + std::sqrt(std::max(sum, 0.0)));
}

bool PixelConverged(const PixelSums& pixel, double noise_threshold) {
    return PixelNoiseError(pixel) < 5 * noise_threshold;
}

uint64_t NoiseThresholdMinSpp(double noise_threshold) {
    const double cycles = std::ceil(16 / std::pow(noise_threshold, 0.3));
    return RoundUpToEven(std::max<uint64_t>(kMinNoiseThresholdSpp, uint64_t(cycles)));
}

uint64_t NextNoiseCheck(uint64_t n, uint64_t max_spp) {
    return std::min(RoundUpToEven(max_spp), n + std::max<uint64_t>(16, RoundUpToEven(n / 4)));
}

absl::Status CheckActivePixels(const RenderTask& task, const AdaptiveSettings& settings) {
    if (task.active_pixels.empty()) return absl::OkStatus();
    const std::string where = absl::StrCat("task ", task.index, ": active pixels: ");
    const int64_t area = task.rect.Area();
    if (task.active_pixels.size() != PixelMask::Bytes(area)) {
        return absl::InvalidArgumentError(absl::StrCat(
            where, task.active_pixels.size(), " bytes, expected ", PixelMask::Bytes(area),
            " (one bit per pixel of ", task.rect.width, "x", task.rect.height, ")"));
    }
    if (const int spare = int(int64_t(task.active_pixels.size()) * 8 - area);
        spare > 0 && (uint8_t(task.active_pixels.back()) >> (8 - spare)) != 0) {
        return absl::InvalidArgumentError(absl::StrCat(where, "a bit past the last pixel is set"));
    }
    if (task.ActivePixels() == 0) {
        return absl::InvalidArgumentError(absl::StrCat(where, "none set"));
    }
    if (settings.noise_threshold <= 0) {
        return absl::InvalidArgumentError(absl::StrCat(where, "a job without a noise threshold"));
    }
    // The plan rounds max_spp up to even (the halves hold equally many), and so may the last pass.
    if (task.sample_end > RoundUpToEven(settings.max_spp)) {
        return absl::InvalidArgumentError(absl::StrCat(where, "samples up to ", task.sample_end,
                                                       ", beyond the job's max_spp ",
                                                       settings.max_spp));
    }
    return absl::OkStatus();
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
    // Per pixel, at least 4 (Cycles' floor): with one sample a half, a dark pixel whose two
    // samples are both 0 would stop at once.
    const uint64_t floor = settings.noise_threshold > 0 ? kMinNoiseThresholdSpp : 2;
    const uint64_t first = std::min(RoundUpToEven(settings.max_spp),
                                    RoundUpToEven(std::max<uint64_t>(first_spp, floor)));
    absl::StatusOr<std::vector<RenderTask>> tiles = PlanRender({width, height, first, tile, 1});
    if (!tiles.ok()) return tiles.status();
    absl::StatusOr<std::unique_ptr<TileStore>> store = make_store(TileRects(*tiles), aovs);
    if (!store.ok()) return store.status();
    std::unique_ptr<AdaptiveTilePlan> plan(
        new AdaptiveTilePlan(width, height, settings, max_task_samples, std::move(*store)));
    plan->first_ = first;
    for (const RenderTask& task : *tiles) {
        plan->tiles_.push_back({.rect = task.rect, .unconverged = task.rect.Area()});
    }
    for (int t = 0; t < int(plan->tiles_.size()); ++t) plan->AppendPass(t, 0, plan->first_);
    return plan;
}

std::vector<RenderTask> AdaptiveTilePlan::AppendPass(int t, uint64_t begin, uint64_t end,
                                                     const std::string& active) {
    Tile& tile = tiles_[size_t(t)];
    const uint64_t pairs = (end - begin) / 2;
    const uint64_t samples = (end - begin) * uint64_t(PixelMask{tile.rect, active}.Count());
    const uint64_t parts = std::min(pairs, (samples + max_task_samples_ - 1) / max_task_samples_);
    std::vector<RenderTask> appended;
    for (uint64_t i = 0; i < parts; ++i) {
        const RenderTask task{int(tasks_.size()), tile.rect, begin + 2 * (pairs * i / parts),
                              begin + 2 * (pairs * (i + 1) / parts), active};
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
    const auto [fewest, most] = std::minmax_element(
        merged->pixels.begin(), merged->pixels.end(),
        [](const PixelSums& a, const PixelSums& b) { return a.Count() < b.Count(); });
    tile.min_spp = fewest->Count();
    tile.spp = most->Count();
    tile.samples = 0;
    for (const PixelSums& pixel : merged->pixels) tile.samples += pixel.Count();
    tile.error = EstimatedTileError(*merged);
    std::erase(tile.pending, t);
    // The pass's other tasks are still out: the tile decides on the whole pass.
    if (!tile.pending.empty()) return std::vector<RenderTask>();
    if (settings_.noise_threshold > 0) return NextNoisePass(tile_index, *merged);
    return NextTilePass(tile_index);
}

std::vector<RenderTask> AdaptiveTilePlan::NextTilePass(int tile_index) {
    const Tile& tile = tiles_[size_t(tile_index)];
    const uint64_t n = tile.spp;
    const bool reached = settings_.target_error > 0 && tile.error <= settings_.target_error;
    if (reached || n >= settings_.max_spp || stopped_) return std::vector<RenderTask>();
    const uint64_t next =
        settings_.target_error > 0
            ? NextSampleCount(n, tile.error, settings_.target_error, settings_.max_spp)
            : std::min(settings_.max_spp, 2 * n);
    return AppendPass(tile_index, n, next);
}

std::vector<RenderTask> AdaptiveTilePlan::NextNoisePass(int tile_index, const TileSums& merged) {
    Tile& tile = tiles_[size_t(tile_index)];
    // The pass's pixels have its end's count (tile.spp); the others converged before.
    const uint64_t n = tile.spp;
    PixelMask next = PixelMask::None(tile.rect);
    tile.unconverged = 0;
    for (size_t i = 0; i < merged.pixels.size(); ++i) {
        const PixelSums& pixel = merged.pixels[i];
        if (pixel.Count() == n && !PixelConverged(pixel, settings_.noise_threshold)) {
            next.Set(i);
            ++tile.unconverged;
        }
    }
    if (tile.unconverged == 0 || n >= settings_.max_spp || stopped_) return {};
    const bool all = tile.unconverged == tile.rect.Area();
    return AppendPass(tile_index, n, NextNoiseCheck(n, settings_.max_spp), all ? "" : next.bits);
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
    uint64_t samples = 0, pixels = 0;
    for (const Tile& tile : tiles_) {
        const uint64_t n = tile.spp;
        samples += tile.samples;
        pixels += uint64_t(tile.rect.Area());
        report.worst_tile_error = std::max(report.worst_tile_error, tile.error);
        if (settings_.target_error > 0 && tile.error > settings_.target_error) {
            ++report.tiles_above_target;
        }
        report.min_spp = std::min(report.min_spp, tile.min_spp);
        report.max_spp = std::max(report.max_spp, n);
        if (settings_.noise_threshold > 0) {
            report.pixels += tile.rect.Area();
            report.pixels_unconverged += tile.unconverged;
        }
        report.per_tile.push_back({tile.rect, n, tile.error});
    }
    report.mean_spp = pixels > 0 ? double(samples) / double(pixels) : 0;
    return report;
}

}  // namespace lf
