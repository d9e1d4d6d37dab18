// Fixed tiles: the planner's tiles and sample passes (lf::PlanRender), each task's sums merged
// by a TileMerger. The base of adaptive tiles and of radiosity's display tiles.
#pragma once

#include <memory>
#include <string>

#include "lf/job/job_execution.h"
#include "lf/job/merge.h"
#include "lf/job/plan.h"

namespace lf {

class TileExecution : public JobExecution {
  public:
    // InvalidArgument for sizes PlanRender refuses; the factory's error when it cannot make the
    // store. Results carry the AOVs `aovs` (lf/core/aov.h).
    static absl::StatusOr<std::unique_ptr<TileExecution>> Make(const RenderPlanSettings& plan,
                                                               const TileStoreFactory& tile_stores,
                                                               uint32_t aovs = 0);

    size_t task_count() const override { return merger_->tasks().size(); }
    int tasks_total() const override { return int(merger_->tasks().size()); }
    size_t tasks_done() const override { return merger_->tasks_done(); }
    bool Complete() const override { return merger_->Complete(); }
    const RenderStats& stats() const override { return merger_->stats(); }
    std::string Summary() const override;
    std::vector<int> Start() override;
    void Lease(int task, const std::string& worker, TaskAssignment& lease) override;
    void Describe(int task, TaskStatus& status) const override;
    uint64_t TaskSamples(int task) const override;
    absl::StatusOr<Merged> Merge(int task, const TaskResult& result) override;
    std::optional<std::string> RecordOf(const TaskResult& result) const override;
    absl::StatusOr<std::vector<int>> MergeRecorded(int task, std::string_view record) override;
    ImageReader SnapshotReader() const override;

  protected:
    TileExecution(std::unique_ptr<TileMerger> merger, uint64_t spp);
    // The fixed plan's merger.
    static absl::StatusOr<std::unique_ptr<TileMerger>> PlanTiles(
        const RenderPlanSettings& plan, const TileStoreFactory& tile_stores, uint32_t aovs);
    TileMerger& merger() const { return *merger_; }
    // Merges a tile's sums; the indices of the tasks the merger appended.
    absl::StatusOr<std::vector<int>> MergeSums(int task, const TileSums& sums);

  private:
    std::unique_ptr<TileMerger> merger_;
    uint64_t spp_;  // for Summary
};

}  // namespace lf
