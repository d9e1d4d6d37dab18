// Adaptive sampling as a plan that grows: every tile starts with one pass, and each pass's
// result decides whether the tile gets another and how many samples it takes. The farm's
// scheduler queues the passes it appends; local mode (lf/local/local_executor.h) runs them on a
// thread pool. A tile's passes depend only on its own samples, so without a time limit the farm
// and local mode plan the same passes and merge the same bits.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/job/merge.h"
#include "lf/job/plan.h"
#include "lf/job/settings.h"
#include "lf/job/tile_store.h"

namespace lf {

// Each tile gets passes of samples until its estimated relative error (EstimatedTileError, the
// square root of its relMSE from the A/B halves) is at most target_error, it has max_spp
// samples, or the time limit has passed. Every tile gets its first pass whatever the time limit.
// With noise_threshold instead, each pixel gets passes until it converges by Cycles' rule
// (PixelConverged); a tile's passes sample only its pixels not converged yet.
struct AdaptiveSettings {
    double target_error = 0;  // relative; 0: none
    double time_limit = 0;    // seconds; 0: none
    uint64_t max_spp = defaults::kAdaptiveMaxSpp;
    double noise_threshold = 0;  // Cycles' Noise Threshold, per pixel; 0: none
};

inline bool IsAdaptive(const AdaptiveSettings& a) {
    return a.target_error > 0 || a.time_limit > 0 || a.noise_threshold > 0;
}

// InvalidArgument naming the setting that is out of range (a negative or non-finite target,
// threshold or limit, max_spp below 2 or above kMaxSpp, a target error with a noise threshold).
absl::Status CheckAdaptiveSettings(const AdaptiveSettings& a);

struct AdaptiveReport {
    double estimated_error = 0;  // of the whole image (EstimatedRelativeError)
    double worst_tile_error = 0;
    int tiles = 0;
    int tiles_above_target = 0;  // stopped by max_spp or the time limit
    bool timed_out = false;
    uint64_t min_spp = 0, max_spp = 0;  // per pixel
    double mean_spp = 0;
    // A noise threshold: the pixels, and those not converged (stopped by max_spp or the time).
    int64_t pixels = 0, pixels_unconverged = 0;
    struct Tile {
        PixelRect rect;
        uint64_t spp = 0;
        double error = 0;  // EstimatedTileError at the end
    };
    std::vector<Tile> per_tile;  // in plan order
};

// The sample count a tile should reach after `n` samples at estimated relative error `error`:
// the error of a mean falls as 1/sqrt(n), so n (error / target)^2, plus 10 % so that a prediction
// a little low does not cost a whole extra pass; at least 2 more, at most 8x per pass so one
// noisy estimate cannot ask for far too much; even, so the A and B halves stay equal.
uint64_t NextSampleCount(uint64_t n, double error, double target, uint64_t max_spp);

// Cycles' per-pixel error (Blender 3.4, kernel/film/adaptive_sampling.h, after Dammertz et al.
// 2009 section 2.1): with I the pixel's mean and A the mean of its even samples,
// sum over channels |I - A| / (1e-4 + sqrt(sum over channels I)). Here I - A = (B - A) / 2.
double PixelNoiseError(const PixelSums& pixel);
// Cycles' test: converged when the error is below 5 threshold (Cycles scales the user's Noise
// Threshold by 5 before comparing, "to make it more intuitive").
bool PixelConverged(const PixelSums& pixel, double noise_threshold);
// The fewest samples a pixel of a noise-threshold render takes, whatever --spp says (Cycles'
// floor too).
inline constexpr uint64_t kMinNoiseThresholdSpp = 4;
// Cycles' automatic min samples for a threshold: ceil(16 / threshold^0.3), at least 4 (0.1: 32,
// 0.01: 64, 0.001: 128), rounded up to even.
uint64_t NoiseThresholdMinSpp(double noise_threshold);
// The samples a pixel not converged after `n` gets next: Cycles checks every 16 samples; passes
// grow by a quarter from 64 on, so a tile takes tens of passes, not thousands, and the check
// points (a function of n alone) are the same for every pixel whatever its tile.
uint64_t NextNoiseCheck(uint64_t n, uint64_t max_spp);

// A task's mask of active pixels as a worker receives it: InvalidArgument unless it is empty or
// one bit per pixel of the rectangle, no bit past it, at least one set, in a job with a noise
// threshold, and the task ends at or below max_spp.
absl::Status CheckActivePixels(const RenderTask& task, const AdaptiveSettings& settings);

// The most pixel samples in one task: a longer pass is split into tasks of consecutive sample
// ranges, so that one hard tile's last pass (up to 8x the one before) spreads over workers
// instead of leaving all but one idle at the end. About a second of one core on the Cornell box.
inline constexpr uint64_t kMaxTaskSamples = uint64_t(1) << 20;

class AdaptiveTilePlan : public TileMerger {
  public:
    // The planner's tiles (PlanRender with one pass), each with a first pass of `first_spp`
    // samples rounded up to even. A pass of more than `max_task_samples` pixel samples is split
    // into tasks of consecutive, even-length sample ranges (so each holds as many A as B
    // samples). Each tile's running sums are kept where `make_store` says. InvalidArgument for
    // sizes PlanRender refuses and for settings CheckAdaptiveSettings refuses; the factory's
    // error when it cannot make the store. Results carry the AOVs `aovs` (lf/core/aov.h).
    static absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> Make(
        int width, int height, uint64_t first_spp, int tile, const AdaptiveSettings& settings,
        uint64_t max_task_samples = kMaxTaskSamples,
        const TileStoreFactory& make_store = MakeMemoryTileStore, uint32_t aovs = 0);

    // The tiles' first passes in plan order, then the passes Merge appends, in the order of the
    // results that asked for them.
    const std::vector<RenderTask>& tasks() const override { return tasks_; }
    // Merges a task; once the last task of a pass is merged, appends the tile's next pass unless
    // the tile is done. InvalidArgument for a result that is not the task's rectangle and sample
    // count, a task not in the plan or one Stop dropped; AlreadyExists for a task merged before;
    // the store's error when it cannot read or write the tile (the task is then not merged).
    absl::StatusOr<std::vector<RenderTask>> Merge(int task_index, const TileSums& sums) override;
    size_t tasks_done() const override { return tasks_done_; }
    bool Complete() const override;
    const RenderStats& stats() const override { return stats_; }

    // The time limit: appends no more passes and drops the tasks not yet merged, except those of
    // tiles' first passes. Returns the dropped task indices. A tile keeps the tasks of a split
    // pass that merged before.
    std::vector<int> Stop();
    bool stopped() const { return stopped_; }
    bool IsPending(int task_index) const;  // planned, neither merged nor dropped
    uint64_t first_spp() const { return first_; }
    size_t tile_count() const { return tiles_.size(); }
    size_t tiles_finished() const;  // tiles with no task out

    // How the sampling ended: TileReport with the estimated error of the Snapshot.
    absl::StatusOr<AdaptiveReport> Report() const;
    // All but estimated_error, without reading the store: a caller may make and measure the
    // snapshot elsewhere (the scheduler does, outside its lock).
    AdaptiveReport TileReport() const;

  private:
    struct Tile {
        PixelRect rect;
        uint64_t spp = 0;      // most samples merged in a pixel
        uint64_t min_spp = 0;  // fewest (a noise threshold stops pixels apart)
        uint64_t samples = 0;  // in all its pixels
        double error = 1;
        int64_t unconverged = 0;   // pixels still sampled, with a noise threshold
        std::vector<int> pending;  // the tasks of the current pass not merged yet
    };
    AdaptiveTilePlan(int width, int height, const AdaptiveSettings& settings,
                     uint64_t max_task_samples, std::shared_ptr<TileStore> store);
    // Appends the tasks of tile `tile`'s pass over samples [begin, end) of the pixels in
    // `active` (PixelMask::bits; empty: all).
    std::vector<RenderTask> AppendPass(int tile, uint64_t begin, uint64_t end,
                                       const std::string& active = {});
    // The pass after one that merged, or none: by the tile's error, or per pixel by the noise
    // threshold.
    std::vector<RenderTask> NextTilePass(int tile);
    std::vector<RenderTask> NextNoisePass(int tile, const TileSums& merged);

    AdaptiveSettings settings_;
    uint64_t max_task_samples_;
    uint64_t first_ = 0;  // samples of the first pass
    std::vector<Tile> tiles_;
    std::vector<RenderTask> tasks_;
    std::vector<int> tile_of_;  // by task
    std::vector<bool> merged_, dropped_;
    size_t tasks_done_ = 0;
    RenderStats stats_;
    bool stopped_ = false;
};

}  // namespace lf
