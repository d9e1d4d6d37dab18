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
    sweeps_.emplace(int(TileExecution::task_count()));
    sweep_input_.clear();
    sweep_input_bytes_.reset();
    return QueueSweep();
}

std::vector<int> SweepExecution::QueueSweep() {
    std::vector<std::vector<int>> tasks;
    std::map<std::string, size_t> task_of_worker;
    for (int c = 0; c < solve_->chunks(); ++c) {
        auto owner = chunk_owner_.find(c);
        // Sweep 0 (no owners yet): a task a chunk. Later, a worker's chunks in one task, in
        // chunk order; a chunk never leased (none: sweep 0 leased them all) goes alone.
        if (solve_->sweep() == 0 || owner == chunk_owner_.end()) {
            tasks.push_back({c});
            continue;
        }
        auto [it, added] = task_of_worker.try_emplace(owner->second.worker, tasks.size());
        if (added) tasks.emplace_back();
        tasks[it->second].push_back(c);
    }
    const std::vector<int> queued = sweeps_->Append(std::move(tasks));
    tasks_ = std::max(tasks_, size_t(sweeps_->end()));
    return queued;
}

std::optional<SweepTaskNumbering::SweepTask> SweepExecution::SweepTaskOf(int task) const {
    return sweeps_ ? sweeps_->FromIndex(task) : std::nullopt;
}

void SweepExecution::Lease(int task, const std::string& worker, TaskAssignment& lease) {
    const std::optional<SweepTaskNumbering::SweepTask> at = SweepTaskOf(task);
    if (!at) {
        TileExecution::Lease(task, worker, lease);
        lease.radiosity_hash = solution_;
        return;
    }
    // The worker of a task's first lease owns its chunks: a second lease of the same task (a
    // straggler's copy, or a retry) must not move them, and with them every later sweep, to a
    // worker that then holds more chunks than the others.
    for (int chunk : at->chunks) {
        ChunkOwner& owner = chunk_owner_[chunk];
        if (owner.task != task) owner = {task, worker};
    }
    lease.task.index = task;
    lease.sweep = at->sweep;
    lease.chunks.assign(at->chunks.begin(), at->chunks.end());
    lease.radiosity_hash = sweep_input_;
    lease.radiosity_input = sweep_input_bytes_;
}

std::string SweepExecution::PreferredWorker(int task) const {
    const std::optional<SweepTaskNumbering::SweepTask> at = SweepTaskOf(task);
    if (!at || at->chunks.empty()) return "";
    auto owner = chunk_owner_.find(at->chunks.front());
    return owner == chunk_owner_.end() ? "" : owner->second.worker;
}

void SweepExecution::Describe(int task, TaskStatus& status) const {
    if (SweepTaskOf(task)) {
        status.kind = TaskKind::kRadiositySweep;
        return;
    }
    TileExecution::Describe(task, status);
}

uint64_t SweepExecution::TaskSamples(int task) const {
    return SweepTaskOf(task) ? 0 : TileExecution::TaskSamples(task);
}

absl::StatusOr<JobExecution::Merged> SweepExecution::Merge(int task, const TaskResult& result) {
    const std::optional<SweepTaskNumbering::SweepTask> at = SweepTaskOf(task);
    if (result.sweeps.empty()) {
        if (at) return absl::InvalidArgumentError("a tile result for a sweep task");
        return TileExecution::Merge(task, result);
    }
    if (!at) return absl::InvalidArgumentError("a sweep result for a tile");
    // Exactly the task's chunks, in its order, of its sweep: checked whole before any is added.
    bool fits = solve_ && at->sweep == solve_->sweep() && result.sweeps.size() == at->chunks.size();
    for (size_t k = 0; fits && k < result.sweeps.size(); ++k) {
        fits = result.sweeps[k].sweep == at->sweep && result.sweeps[k].chunk == at->chunks[k];
    }
    if (!fits) {
        std::string chunks;
        for (const SweepChunkResult& r : result.sweeps) {
            absl::StrAppend(&chunks, chunks.empty() ? "" : ", ", r.chunk, " of sweep ", r.sweep);
        }
        return absl::InvalidArgumentError(
            absl::StrCat("a result of chunks ", chunks, " for task ", task));
    }
    if (absl::Status added = solve_->Add(result.sweeps); !added.ok()) return added;
    // Done by another worker while their owner is gone (a retry after it was lost): that worker
    // holds their rows now, and later sweeps go there, not to a third worker that would compute
    // them again. It may then hold more chunks than the others; computing a chunk's rows costs
    // far more than sweeping it (the Cornell box at 0.02: 2.2 s of links against 14 ms a sweep),
    // so that is cheaper than spreading them again. A straggler's copy that won while the owner
    // lives leaves them there: both hold the rows.
    if (!result.takes_over.empty()) {
        for (int chunk : at->chunks) chunk_owner_[chunk].worker = result.takes_over;
    }
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
    if (!result.sweeps.empty()) return std::nullopt;
    return TileExecution::RecordOf(result);
}

absl::StatusOr<std::vector<int>> SweepExecution::Publish(bool converged, const std::string& hash,
                                                         std::shared_ptr<const std::string> bytes) {
    if (!solve_) return absl::FailedPreconditionError("radiosity: no solve under way");
    if (!converged) {
        sweep_input_ = hash;
        sweep_input_bytes_ = std::move(bytes);
        return QueueSweep();
    }
    // Every display tile's lease would carry it: the tiles read a stored blob.
    if (bytes) return absl::InvalidArgumentError("radiosity: a solution that is not stored");
    solution_ = hash;
    sweep_input_.clear();  // no sweep reads it again
    sweep_input_bytes_.reset();
    solve_.reset();
    return Start();
}

void SweepExecution::AddBlobsInUse(std::set<std::string>& hashes) const {
    // One whose bytes go with the leases was never stored.
    if (!sweep_input_.empty() && !sweep_input_bytes_) hashes.insert(sweep_input_);
    if (!solution_.empty()) hashes.insert(solution_);
}

}  // namespace lf
