#include "lf/job/splat_execution.h"

#include "absl/strings/str_cat.h"
#include "lf/job/splat_result_codec.h"

namespace lf {

absl::StatusOr<std::unique_ptr<SplatExecution>> SplatExecution::Make(
    const SplatPlanSettings& plan, const TileStoreFactory& tile_stores) {
    absl::StatusOr<std::vector<SplatTask>> tasks = PlanSplatRender(plan);
    if (!tasks.ok()) return tasks.status();
    absl::StatusOr<std::unique_ptr<SplatMerger>> merger = SplatMerger::Make(
        plan.width, plan.height, plan.tile, plan.kind, std::move(*tasks), tile_stores);
    if (!merger.ok()) return merger.status();
    return std::unique_ptr<SplatExecution>(new SplatExecution(plan, std::move(*merger)));
}

std::string SplatExecution::Summary() const {
    return absl::StrCat(task_count(), " tasks, ", plan_.width, "x", plan_.height, ", ", plan_.spp,
                        " spp");
}

std::vector<int> SplatExecution::Start() {
    std::vector<int> tasks(task_count());
    for (size_t t = 0; t < tasks.size(); ++t) tasks[t] = int(t);
    return tasks;
}

void SplatExecution::Lease(int index, const std::string& worker, TaskAssignment& lease) {
    const SplatTask& frame = task(index);
    lease.task = RenderTask{frame.index, frame.rect, frame.sample_begin, frame.sample_end};
    lease.path_begin = frame.path_begin;
    lease.path_end = frame.path_end;
}

void SplatExecution::Describe(int index, TaskStatus& status) const {
    const SplatTask& frame = task(index);
    status.kind = TaskKind::kSplat;
    // A light-path task has no camera part: it covers the frame.
    const PixelRect rect =
        frame.rect.width > 0 ? frame.rect : PixelRect{0, 0, plan_.width, plan_.height};
    status.x = rect.x0;
    status.y = rect.y0;
    status.width = rect.width;
    status.height = rect.height;
    status.samples = frame.sample_end - frame.sample_begin;
}

uint64_t SplatExecution::TaskSamples(int index) const {
    const SplatTask& t = task(index);
    return uint64_t(t.rect.width) * uint64_t(t.rect.height) * (t.sample_end - t.sample_begin);
}

absl::StatusOr<JobExecution::Merged> SplatExecution::Merge(int index, const TaskResult& result) {
    if (!result.sweeps.empty()) return absl::InvalidArgumentError("a sweep result for a tile");
    if (!result.splats || !result.sums) {
        return absl::InvalidArgumentError("a splat task's result without its splats");
    }
    // Frame plans are fixed: a merge appends no task.
    if (absl::Status added = merger_->Add(index, *result.sums, *result.splats); !added.ok()) {
        return added;
    }
    return Merged{};
}

std::optional<std::string> SplatExecution::RecordOf(const TaskResult& result) const {
    if (!result.sums || !result.splats) return std::nullopt;  // not a splat task's result
    return EncodeSplatResult(*result.sums, *result.splats);
}

absl::StatusOr<std::vector<int>> SplatExecution::MergeRecorded(int index, std::string_view record) {
    absl::StatusOr<SplatResult> result = DecodeSplatResult(record);
    if (!result.ok()) return result.status();
    if (absl::Status added = merger_->Add(index, result->camera, result->splats); !added.ok()) {
        return added;
    }
    return std::vector<int>{};
}

JobExecution::ImageReader SplatExecution::SnapshotReader() const {
    // A preview may show a tile merged meanwhile with the normalisation before it; a complete
    // job's is exact.
    return [source = merger_->snapshot_source()] { return source.Read(); };
}

}  // namespace lf
