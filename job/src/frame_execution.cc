#include "lf/job/frame_execution.h"

#include "absl/strings/str_cat.h"
#include "lf/job/frame_result_codec.h"

namespace lf {

absl::StatusOr<std::unique_ptr<FrameExecution>> FrameExecution::Make(
    const FramePlanSettings& plan, const TileStoreFactory& tile_stores) {
    absl::StatusOr<std::vector<FrameTask>> tasks = PlanFrameRender(plan);
    if (!tasks.ok()) return tasks.status();
    absl::StatusOr<std::unique_ptr<FrameMerger>> merger = FrameMerger::Make(
        plan.width, plan.height, plan.tile, plan.kind, std::move(*tasks), tile_stores);
    if (!merger.ok()) return merger.status();
    return std::unique_ptr<FrameExecution>(new FrameExecution(plan, std::move(*merger)));
}

std::string FrameExecution::Summary() const {
    return absl::StrCat(task_count(), " tasks, ", plan_.width, "x", plan_.height, ", ", plan_.spp,
                        " spp");
}

std::vector<int> FrameExecution::Start() {
    std::vector<int> tasks(task_count());
    for (size_t t = 0; t < tasks.size(); ++t) tasks[t] = int(t);
    return tasks;
}

void FrameExecution::Lease(int index, const std::string& worker, TaskAssignment& lease) {
    const FrameTask& frame = task(index);
    lease.task = RenderTask{frame.index, frame.rect, frame.sample_begin, frame.sample_end};
    lease.path_begin = frame.path_begin;
    lease.path_end = frame.path_end;
}

void FrameExecution::Describe(int index, TaskStatus& status) const {
    const FrameTask& frame = task(index);
    status.kind = TaskKind::kFrame;
    // A light-path task has no camera part: it covers the frame.
    const PixelRect rect =
        frame.rect.width > 0 ? frame.rect : PixelRect{0, 0, plan_.width, plan_.height};
    status.x = rect.x0;
    status.y = rect.y0;
    status.width = rect.width;
    status.height = rect.height;
    status.samples = frame.sample_end - frame.sample_begin;
}

uint64_t FrameExecution::TaskSamples(int index) const {
    const FrameTask& t = task(index);
    return uint64_t(t.rect.width) * uint64_t(t.rect.height) * (t.sample_end - t.sample_begin);
}

absl::StatusOr<JobExecution::Merged> FrameExecution::Merge(int index, const TaskResult& result) {
    if (result.sweep) return absl::InvalidArgumentError("a sweep result for a tile");
    if (!result.splats || !result.sums) {
        return absl::InvalidArgumentError("a frame task's result without its splats");
    }
    // Frame plans are fixed: a merge appends no task.
    if (absl::Status added = merger_->Add(index, *result.sums, *result.splats); !added.ok()) {
        return added;
    }
    return Merged{};
}

std::optional<std::string> FrameExecution::RecordOf(const TaskResult& result) const {
    return EncodeFrameResult(*result.sums, *result.splats);
}

absl::StatusOr<std::vector<int>> FrameExecution::MergeRecorded(int index, std::string_view record) {
    absl::StatusOr<FrameResult> result = DecodeFrameResult(record);
    if (!result.ok()) return result.status();
    if (absl::Status added = merger_->Add(index, result->camera, result->splats); !added.ok()) {
        return added;
    }
    return std::vector<int>{};
}

JobExecution::ImageReader FrameExecution::SnapshotReader() const {
    // A preview may show a tile merged meanwhile with the normalisation before it; a complete
    // job's is exact.
    return [source = merger_->snapshot_source()] { return source.Read(); };
}

}  // namespace lf
