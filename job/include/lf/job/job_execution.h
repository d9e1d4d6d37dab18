// How one kind of job runs, apart from whoever runs it: its plan, its merger, which tasks start
// it and which a result appends or unlocks, its time limit, and what a task's result means. The
// coordinator's scheduler (lf/server/scheduler.h) asks a job's JobExecution for everything
// kind-specific, and local mode (lf/local/local_executor.h) runs the same objects on threads.
//
// The kinds: fixed tiles (lf/job/tile_execution.h), adaptive tiles
// (lf/job/adaptive_tile_execution.h), splat passes of the splatting methods
// (lf/job/splat_execution.h), and radiosity solved in sweeps (lf/job/sweep_execution.h).
// MakeJobExecution chooses one from a job spec, in one place.
//
// Not thread-safe: the caller serialises every call.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/core/radiosity_codec.h"
#include "lf/core/splat_list.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/job_spec.h"
#include "lf/job/radiosity_solve.h"
#include "lf/job/task_assignment.h"
#include "lf/job/task_status.h"
#include "lf/job/tile_store.h"

namespace lf {

// A task's result as a worker (or a local thread) made it; which parts are set depends on the
// task: a tile's sums, a splat task's camera sums and splats, a patch-group task's sweep chunk.
struct TaskResult {
    const TileSums* sums = nullptr;
    // The bytes `sums` was decoded from (lf::DecodeTileSums), valid for the call, when the
    // caller has them: a tile's record is then those bytes, not an encoding of `sums` made
    // again (1.7 MB a 128x128 tile, under the scheduler's lock). They decode to `sums`, in
    // whichever version of the encoding the worker sent.
    std::string_view encoded_sums;
    SplatList* splats = nullptr;  // coalesced by the merge
    // A radiosity sweep task's: one result a chunk of its lease, in that order.
    std::span<const SweepChunkResult> sweeps;
    // A shot's: the frame the worker rendered (its lease's); a chunk's: one result a part of its
    // lease, in that order.
    std::optional<int> frame;
    std::vector<TaskResult> parts;
    // What it cost on the worker: a chunk's whole lease, and each part its own.
    TaskTimes times;
    // The farm's worker that made it, when the task's preferred worker (PreferredWorker) is
    // gone or may not take it now: the execution may prefer this one from now on. Empty when
    // the preferred worker made it or may still take it (a straggler's copy that won), and in
    // local mode.
    std::string takes_over;
};

class JobExecution {
  public:
    virtual ~JobExecution() = default;

    // Tasks planned so far, by index; those of the image (planned and not dropped: what
    // JobRecord::tasks_total says); and those of the image merged.
    virtual size_t task_count() const = 0;
    virtual int tasks_total() const = 0;
    virtual size_t tasks_done() const = 0;
    // Every task of the image merged (or dropped) and none left to plan.
    virtual bool Complete() const = 0;
    virtual const RenderStats& stats() const = 0;
    // For the log line of a submission: "4 tiles, 16x16, ..." as the kind describes itself.
    virtual std::string Summary() const = 0;

    // The tasks to queue when the job starts, or starts again after a restart: the caller
    // queues those among them not yet done. A radiosity job not yet solved starts with its
    // first sweep, and may grow task_count() here.
    virtual std::vector<int> Start() = 0;
    // The order local mode runs queued tasks in: lowest first (ties by index).
    virtual uint64_t QueueRank(int task) const { return 0; }

    // What task `task`'s lease tells `worker` (its pixels, samples, paths, sweep chunk and the
    // blob it reads); the job's id and spec are the caller's.
    virtual void Lease(int task, const std::string& worker, TaskAssignment& lease) = 0;
    // The worker a queued task should go to while that worker lives ("" for any): a sweep
    // chunk's last worker keeps its form-factor rows.
    virtual std::string PreferredWorker(int task) const { return ""; }
    // A task's kind, pixels and samples, as `lightfarm tasks` shows them.
    virtual void Describe(int task, TaskStatus& status) const = 0;
    // Pixels times samples per pixel of a task's camera part (0 for a sweep's), for throughput.
    virtual uint64_t TaskSamples(int task) const = 0;
    // How many parts a task's result must hold (TaskResult::parts): a chunk's frames' tasks;
    // 0 for a task answered by one result. Checked before a result is decoded.
    virtual size_t ResultParts(int task) const { return 0; }

    struct Merged {
        std::vector<int> appended;  // tasks the result added to the plan, to queue
        std::optional<RadiositySolve::Outcome> sweep;  // the sweep this result completed
        absl::Status job_error;             // not ok: the job fails (a solve out of iterations)
        std::vector<int> frames_completed;  // a shot's frames this result completed
    };
    // Validates and merges task `task`'s result. InvalidArgument (nothing merged) for a result
    // that is not the task's: another kind, another rectangle or sample count, another frame.
    virtual absl::StatusOr<Merged> Merge(int task, const TaskResult& result) = 0;
    // What the job store keeps of a merged result, so that a restart merges it again
    // (MergeRecorded); nullopt for soft state (a sweep's result: the solve runs again).
    virtual std::optional<std::string> RecordOf(const TaskResult& result) const = 0;
    // Merges a result the store recorded again; returns the tasks it appended.
    virtual absl::StatusOr<std::vector<int>> MergeRecorded(int task, std::string_view record) = 0;

    // The time limit: once it has passed since `started`, the tasks it drops (never a tile's
    // first pass); nullopt when it has not passed, or was enforced before.
    virtual std::optional<std::vector<int>> EnforceTimeLimit(absl::Time started, absl::Time now) {
        return std::nullopt;
    }
    // The kinds whose tasks the time limit may drop say when it passes.
    virtual std::optional<absl::Duration> time_limit() const { return std::nullopt; }

    // A radiosity solve's sweep stored as blob `hash` (or, a sweep's input, not stored: its
    // `bytes` go with the leases; a solution must be stored): the next sweep's tasks, or
    // (converged) the display tiles, to queue. FailedPrecondition for a job that is not solved
    // in sweeps.
    virtual absl::StatusOr<std::vector<int>> Publish(
        bool converged, const std::string& hash,
        std::shared_ptr<const std::string> bytes = nullptr);
    // The blobs the job reads beyond its spec's (a sweep's input, the solution).
    virtual void AddBlobsInUse(std::set<std::string>& hashes) const {}

    // Reads the image of everything merged so far; safe to call after the caller's lock is
    // released (it shares the stores), a preview then showing tiles merged meanwhile.
    using ImageReader = std::function<absl::StatusOr<Image>()>;
    virtual ImageReader SnapshotReader() const = 0;
    // An adaptive job's report, without estimated_error (measured on the snapshot).
    virtual std::optional<AdaptiveReport> TileReport() const { return std::nullopt; }

    // A shot's frames in frame order, without result paths (the coordinator's); none for a still.
    virtual std::vector<FrameProgress> Frames() const { return {}; }
    // A shot's frame `frame` (its number) as its own execution: its image, stats and report;
    // nullptr for a frame the job does not render.
    virtual const JobExecution* FrameExecution(int frame) const { return nullptr; }
};

// The kind of execution `spec` runs as, planned as its settings say; InvalidArgument when they
// cannot be. `spec` must be validated. A shot (spec.shot.frames set, even one frame) is a
// ShotExecution (lf/job/shot_execution.h) of the frames' own executions.
absl::StatusOr<std::unique_ptr<JobExecution>> MakeJobExecution(const JobSpec& spec,
                                                               const TileStoreFactory& tile_stores);
// The kind one image of `spec` runs as: the still, or a shot's frame (FrameSpec), whose
// shot settings it does not read.
absl::StatusOr<std::unique_ptr<JobExecution>> MakeFrameExecution(
    const JobSpec& spec, const TileStoreFactory& tile_stores);

}  // namespace lf
