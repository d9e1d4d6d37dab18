// Frame passes of the splatting methods (light, bdpt, ppm): the fixed plan of
// lf::PlanFrameRender, each task's camera sums and splat list merged by a FrameMerger.
#pragma once

#include <memory>

#include "lf/job/frame_merge.h"
#include "lf/job/frame_plan.h"
#include "lf/job/job_execution.h"

namespace lf {

class FrameExecution : public JobExecution {
  public:
    // The merger's tiles where `tile_stores` says; InvalidArgument for a plan PlanFrameRender
    // refuses.
    static absl::StatusOr<std::unique_ptr<FrameExecution>> Make(
        const FramePlanSettings& plan, const TileStoreFactory& tile_stores);

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
    // The camera sums and the splats, in one record (lf/job/frame_result_codec.h).
    std::optional<std::string> RecordOf(const TaskResult& result) const override;
    absl::StatusOr<std::vector<int>> MergeRecorded(int task, std::string_view record) override;
    ImageReader SnapshotReader() const override;

    const FrameTask& task(int index) const { return merger_->tasks()[size_t(index)]; }

  private:
    FrameExecution(const FramePlanSettings& plan, std::unique_ptr<FrameMerger> merger)
        : plan_(plan), merger_(std::move(merger)) {}

    FramePlanSettings plan_;
    std::unique_ptr<FrameMerger> merger_;
};

}  // namespace lf
