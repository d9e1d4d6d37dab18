// Radiosity solved in sweeps: the solve's patch-group tasks (lf::RadiositySolve, numbered by
// SweepTaskNumbering after the tiles) come first, a sweep at a time, each sweep's result stored
// by the caller as a blob (Publish); once solved, the display tiles, which read the solution.
// Sweep 0 has a task a chunk, leased one at a time, so the workers share the linking, whose
// cost per chunk is not known before; the worker of a chunk's first lease keeps its rows, and
// each later sweep has one task a worker holding chunks, covering all of them: one lease,
// heartbeat and result a worker and sweep instead of one a chunk. That is soft state: any
// worker may take a task whose worker is gone, and its result makes it the chunks' owner
// (TaskResult::takes_over): it holds their rows.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "lf/job/radiosity_solve.h"
#include "lf/job/sweep_task_numbering.h"
#include "lf/job/tile_execution.h"

namespace lf {

class SweepExecution : public TileExecution {
  public:
    // A display tile's sample costs about one ray: tiles of fewer samples a pass than this are
    // widened (up to the farm's tile limit), so a task's lease and result round trip stay small
    // beside its work. The pixels do not depend on the tiles.
    static constexpr uint64_t kMinDisplayTaskSamples = uint64_t(1) << 18;
    static RenderPlanSettings DisplayPlan(RenderPlanSettings plan, uint32_t aovs);

    static absl::StatusOr<std::unique_ptr<SweepExecution>> Make(const RenderPlanSettings& plan,
                                                                const RadiositySettings& radiosity,
                                                                const TileStoreFactory& tile_stores,
                                                                uint32_t aovs = 0);

    size_t task_count() const override { return tasks_; }
    // Not solved yet (after a restart too: the solve is not recorded, and runs again to the same
    // bits): the first sweep; else the tiles.
    std::vector<int> Start() override;
    void Lease(int task, const std::string& worker, TaskAssignment& lease) override;
    std::string PreferredWorker(int task) const override;
    void Describe(int task, TaskStatus& status) const override;
    uint64_t TaskSamples(int task) const override;
    absl::StatusOr<Merged> Merge(int task, const TaskResult& result) override;
    std::optional<std::string> RecordOf(const TaskResult& result) const override;
    absl::StatusOr<std::vector<int>> Publish(
        bool converged, const std::string& hash,
        std::shared_ptr<const std::string> bytes = nullptr) override;
    void AddBlobsInUse(std::set<std::string>& hashes) const override;

  private:
    SweepExecution(std::unique_ptr<TileMerger> merger, uint64_t spp,
                   const RadiositySettings& radiosity);
    // The sweep and chunks of a patch-group task; nullopt for a tile's.
    std::optional<SweepTaskNumbering::SweepTask> SweepTaskOf(int task) const;
    // Grows the tasks by the current sweep's, and returns them.
    std::vector<int> QueueSweep();

    RadiositySettings radiosity_;
    size_t tasks_;                           // the tiles, then the sweeps' tasks planned so far
    std::unique_ptr<RadiositySolve> solve_;  // while solving
    std::optional<SweepTaskNumbering> sweeps_;
    std::string sweep_input_;  // blob of the current sweep's input; "" in sweep 0
    std::shared_ptr<const std::string> sweep_input_bytes_;  // its bytes, when not stored
    std::string solution_;                                  // blob of the solution, once solved
    struct ChunkOwner {
        int task = -1;  // the chunk's last task leased
        std::string worker;
    };
    std::map<int, ChunkOwner> chunk_owner_;
};

}  // namespace lf
