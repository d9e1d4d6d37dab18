// Adaptive tiles: an AdaptiveTilePlan whose passes are appended as results ask for them, run
// least sampled first, until each tile reaches its target or the time limit drops the passes
// not yet merged (lf/job/time_limit.h).
#pragma once

#include <memory>

#include "lf/job/adaptive_plan.h"
#include "lf/job/tile_execution.h"

namespace lf {

class AdaptiveTileExecution : public TileExecution {
  public:
    // As AdaptiveTilePlan::Make: every tile's first pass of `first_spp` samples rounded up to
    // even, passes split into tasks of at most `max_task_samples` pixel samples.
    static absl::StatusOr<std::unique_ptr<AdaptiveTileExecution>> Make(
        int width, int height, uint64_t first_spp, int tile, const AdaptiveSettings& settings,
        uint64_t max_task_samples, const TileStoreFactory& tile_stores, uint32_t aovs = 0);

    int tasks_total() const override { return int(task_count()) - dropped_; }
    std::string Summary() const override;
    std::vector<int> Start() override;
    // Every tile's first pass before any second one, the least sampled tiles first, so that a
    // time limit leaves the tiles evenly sampled.
    uint64_t QueueRank(int task) const override;
    std::optional<std::vector<int>> EnforceTimeLimit(absl::Time started, absl::Time now) override;
    std::optional<absl::Duration> time_limit() const override;
    std::optional<AdaptiveReport> TileReport() const override { return plan().TileReport(); }
    size_t tile_count() const { return plan().tile_count(); }
    size_t tiles_finished() const { return plan().tiles_finished(); }
    // The report with the image's estimated error (reads the store).
    absl::StatusOr<AdaptiveReport> Report() const { return plan().Report(); }

  private:
    AdaptiveTileExecution(std::unique_ptr<AdaptiveTilePlan> plan, const AdaptiveSettings& settings);
    AdaptiveTilePlan& plan() const { return static_cast<AdaptiveTilePlan&>(merger()); }

    AdaptiveSettings settings_;
    int dropped_ = 0;
};

}  // namespace lf
