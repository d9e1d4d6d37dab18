#include "lf/job/tile_execution.h"

#include "absl/strings/str_cat.h"
#include "lf/core/tile_codec.h"

namespace lf {

absl::StatusOr<std::unique_ptr<TileMerger>> TileExecution::PlanTiles(
    const RenderPlanSettings& plan, const TileStoreFactory& tile_stores, uint32_t aovs) {
    absl::StatusOr<std::vector<RenderTask>> tasks = PlanRender(plan);
    if (!tasks.ok()) return tasks.status();
    absl::StatusOr<std::unique_ptr<RenderMerger>> merger =
        RenderMerger::Make(plan.width, plan.height, std::move(*tasks), tile_stores, aovs);
    if (!merger.ok()) return merger.status();
    return std::unique_ptr<TileMerger>(std::move(*merger));
}

absl::StatusOr<std::unique_ptr<TileExecution>> TileExecution::Make(
    const RenderPlanSettings& plan, const TileStoreFactory& tile_stores, uint32_t aovs) {
    absl::StatusOr<std::unique_ptr<TileMerger>> merger = PlanTiles(plan, tile_stores, aovs);
    if (!merger.ok()) return merger.status();
    return std::unique_ptr<TileExecution>(new TileExecution(std::move(*merger), plan.spp));
}

TileExecution::TileExecution(std::unique_ptr<TileMerger> merger, uint64_t spp)
    : merger_(std::move(merger)), spp_(spp) {}

std::string TileExecution::Summary() const {
    return absl::StrCat(task_count(), " tasks, ", merger_->width(), "x", merger_->height(), ", ",
                        spp_, " spp");
}

std::vector<int> TileExecution::Start() {
    std::vector<int> tasks(merger_->tasks().size());
    for (size_t t = 0; t < tasks.size(); ++t) tasks[t] = int(t);
    return tasks;
}

void TileExecution::Lease(int task, const std::string& worker, TaskAssignment& lease) {
    lease.task = merger_->tasks()[size_t(task)];
}

void TileExecution::Describe(int task, TaskStatus& status) const {
    const RenderTask& tile = merger_->tasks()[size_t(task)];
    status.kind = TaskKind::kTile;
    status.x = tile.rect.x0;
    status.y = tile.rect.y0;
    status.width = tile.rect.width;
    status.height = tile.rect.height;
    status.samples = tile.sample_end - tile.sample_begin;
}

uint64_t TileExecution::TaskSamples(int task) const {
    return merger_->tasks()[size_t(task)].Samples();
}

absl::StatusOr<std::vector<int>> TileExecution::MergeSums(int task, const TileSums& sums) {
    absl::StatusOr<std::vector<RenderTask>> appended = merger_->Merge(task, sums);
    if (!appended.ok()) return appended.status();
    std::vector<int> indices;
    for (const RenderTask& pass : *appended) indices.push_back(pass.index);
    return indices;
}

absl::StatusOr<JobExecution::Merged> TileExecution::Merge(int task, const TaskResult& result) {
    if (!result.sweeps.empty()) return absl::InvalidArgumentError("a sweep result for a tile");
    if (result.splats) return absl::InvalidArgumentError("splats in the result of a tile task");
    if (!result.sums) return absl::InvalidArgumentError("a tile task's result without its sums");
    absl::StatusOr<std::vector<int>> appended = MergeSums(task, *result.sums);
    if (!appended.ok()) return appended.status();
    return Merged{.appended = std::move(*appended)};
}

std::optional<std::string> TileExecution::RecordOf(const TaskResult& result) const {
    if (!result.sums) return std::nullopt;  // not a tile's result: nothing to record
    if (!result.encoded_sums.empty()) return std::string(result.encoded_sums);
    return EncodeTileSums(*result.sums);
}

absl::StatusOr<std::vector<int>> TileExecution::MergeRecorded(int task, std::string_view record) {
    absl::StatusOr<TileSums> sums = DecodeTileSums(record);
    if (!sums.ok()) return sums.status();
    return MergeSums(task, *sums);
}

JobExecution::ImageReader TileExecution::SnapshotReader() const {
    return [store = merger_->store(), width = merger_->width(), height = merger_->height()] {
        return RenderImageOf(*store, width, height);
    };
}

}  // namespace lf
