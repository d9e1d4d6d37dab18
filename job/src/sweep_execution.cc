#include "lf/job/sweep_execution.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "lf/job/job_spec.h"

namespace lf {

RenderPlanSettings SweepExecution::DisplayPlan(RenderPlanSettings plan, uint32_t aovs) {
    const int limit = aovs == 0 ? kMaxFarmTile : kMaxFarmAovTile;
    const uint64_t pass_spp = std::max<uint64_t>(1, plan.spp / uint64_t(std::max(1, plan.passes)));
    while (plan.tile < limit &&
           uint64_t(plan.tile) * uint64_t(plan.tile) * pass_spp < kMinDisplayTaskSamples) {
        plan.tile = std::min(2 * plan.tile, limit);
    }
    return plan;
}

absl::StatusOr<std::unique_ptr<SweepExecution>> SweepExecution::Make(
    const RenderPlanSettings& plan, const RadiositySettings& radiosity,
    const TileStoreFactory& tile_stores, uint32_t aovs) {
    absl::StatusOr<std::unique_ptr<TileMerger>> merger =
        PlanTiles(DisplayPlan(plan, aovs), tile_stores, aovs);
    if (!merger.ok()) return merger.status();
    return std::unique_ptr<SweepExecution>(
        new SweepExecution(std::move(*merger), plan.spp, radiosity));
}

SweepExecution::SweepExecution(std::unique_ptr<TileMerger> merger, uint64_t spp,
                               const RadiositySettings& radiosity)
    : TileExecution(std::move(merger), spp),
      radiosity_(radiosity),
      tasks_(TileExecution::task_count()) {}

std::vector<int> SweepExecution::Start() {
    if (!solution_.empty() || merger().Complete()) return TileExecution::Start();
    solve_ = std::make_unique<RadiositySolve>(radiosity_.sweep_tasks, radiosity_.tolerance,
                                              radiosity_.max_iterations);
    sweeps_ = SweepTaskNumbering{int(TileExecution::task_count()), solve_->chunks()};
    sweep_input_.clear();
    return QueueSweep();
}

std::vector<int> SweepExecution::QueueSweep() {
    const int sweep = solve_->sweep();
    tasks_ = std::max(tasks_, size_t(sweeps_->ToIndex({sweep + 1, 0})));
    std::vector<int> queued;
    for (int c = 0; c < sweeps_->chunks; ++c) queued.push_back(sweeps_->ToIndex({sweep, c}));
    return queued;
}

std::optional<SweepTaskNumbering::SweepChunk> SweepExecution::SweepChunkOf(int task) const {
    return sweeps_ ? sweeps_->FromIndex(task) : std::nullopt;
}

void SweepExecution::Lease(int task, const std::string& worker, TaskAssignment& lease) {
    const std::optional<SweepTaskNumbering::SweepChunk> at = SweepChunkOf(task);
    if (!at) {
        TileExecution::Lease(task, worker, lease);
        lease.radiosity_hash = solution_;
        return;
    }
    // The worker of a task's first lease owns the chunk: a second lease of the same task (a
    // straggler's copy, or a retry) must not move the chunk, and with it every later sweep of
    // it, to a worker that then holds more chunks than the others.
    ChunkOwner& owner = chunk_owner_[at->chunk];
    if (owner.task != task) owner = {task, worker};
    lease.task.index = task;
    lease.sweep = at->sweep;
    lease.chunk = at->chunk;
    lease.radiosity_hash = sweep_input_;
}

std::string SweepExecution::PreferredWorker(int task) const {
    const std::optional<SweepTaskNumbering::SweepChunk> at = SweepChunkOf(task);
    if (!at) return "";
    auto owner = chunk_owner_.find(at->chunk);
    return owner == chunk_owner_.end() ? "" : owner->second.worker;
}

void SweepExecution::Describe(int task, TaskStatus& status) const {
    if (SweepChunkOf(task)) {
        status.kind = TaskKind::kRadiositySweep;
        return;
    }
    TileExecution::Describe(task, status);
}

uint64_t SweepExecution::TaskSamples(int task) const {
    return SweepChunkOf(task) ? 0 : TileExecution::TaskSamples(task);
}

absl::StatusOr<JobExecution::Merged> SweepExecution::Merge(int task, const TaskResult& result) {
    const std::optional<SweepTaskNumbering::SweepChunk> at = SweepChunkOf(task);
    if (!result.sweep) {
        if (at) return absl::InvalidArgumentError("a tile result for a sweep task");
        return TileExecution::Merge(task, result);
    }
    const SweepChunkResult& sweep = *result.sweep;
    if (!at) return absl::InvalidArgumentError("a sweep result for a tile");
    if (*at != SweepTaskNumbering::SweepChunk{sweep.sweep, sweep.chunk} || !solve_) {
        return absl::InvalidArgumentError(
            absl::StrCat("a result of sweep ", sweep.sweep, " chunk ", sweep.chunk));
    }
    if (absl::Status added = solve_->Add(sweep); !added.ok()) return added;
    Merged merged;
    if (solve_->SweepComplete()) {
        absl::StatusOr<RadiositySolve::Outcome> outcome = solve_->FinishSweep();
        if (outcome.ok()) {
            merged.sweep = std::move(*outcome);
        } else {
            merged.job_error = outcome.status();
        }
    }
    return merged;
}

std::optional<std::string> SweepExecution::RecordOf(const TaskResult& result) const {
    if (result.sweep) return std::nullopt;
    return TileExecution::RecordOf(result);
}

absl::StatusOr<std::vector<int>> SweepExecution::Publish(bool converged, const std::string& hash) {
    if (!solve_) return absl::FailedPreconditionError("radiosity: no solve under way");
    if (!converged) {
        sweep_input_ = hash;
        return QueueSweep();
    }
    solution_ = hash;
    solve_.reset();
    return Start();
}

void SweepExecution::AddBlobsInUse(std::set<std::string>& hashes) const {
    for (const std::string* hash : {&sweep_input_, &solution_}) {
        if (!hash->empty()) hashes.insert(*hash);
    }
}

}  // namespace lf
