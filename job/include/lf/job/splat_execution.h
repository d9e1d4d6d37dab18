// Splat passes of the splatting methods (light, bdpt, ppm): the fixed plan of
// lf::PlanSplatRender, each task's camera sums and splat list merged by a SplatMerger.
#pragma once

#include <memory>

#include "lf/job/splat_merge.h"
#include "lf/job/splat_plan.h"
#include "lf/job/job_execution.h"

namespace lf {

class SplatExecution : public JobExecution {
  public:
    // The merger's tiles where `tile_stores` says; InvalidArgument for a plan PlanSplatRender
    // refuses.
    static absl::StatusOr<std::unique_ptr<SplatExecution>> Make(
        const SplatPlanSettings& plan, const TileStoreFactory& tile_stores);

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
    // The camera sums and the splats, in one record (lf/job/splat_result_codec.h).
    std::optional<std::string> RecordOf(const TaskResult& result) const override;
    absl::StatusOr<std::vector<int>> MergeRecorded(int task, std::string_view record) override;
    ImageReader SnapshotReader() const override;

    const SplatTask& task(int index) const { return merger_->tasks()[size_t(index)]; }

  private:
    SplatExecution(const SplatPlanSettings& plan, std::unique_ptr<SplatMerger> merger)
        : plan_(plan), merger_(std::move(merger)) {}

    SplatPlanSettings plan_;
    std::unique_ptr<SplatMerger> merger_;
};

}  // namespace lf
