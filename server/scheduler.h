// The farm's scheduler, without I/O or gRPC: jobs are planned into tasks, tasks are leased to
// workers by job priority then age, leases live while heartbeats extend them, and results merge
// into the job's image. Tile jobs merge through a TileMerger, frame-method jobs (light, bdpt, ppm)
// through a FrameMerger (lf/job/frame_merge.h), whose results carry splats. It composes small
// units, each tested alone: task states change only through TaskStateMachine, job states through
// TransitionJob; LeaseTimeouts keeps the lease deadlines, WorkerRegistry the live workers,
// SpeculationPolicy and TimeLimitReached decide second leases and time limits, SweepTaskNumbering
// places a solve's tasks; the timeout checker (TimeoutChecker) calls ExpireLeases and
// EnforceTimeLimits. The store is never read, nor waited for, under the scheduler's lock.
//
// A lease that expires or a failure puts the task back in the queue, where workers it has not
// failed on take it first; the third counted failure fails the job. Cancelling a job drops all its
// tasks at once: their heartbeats answer "stop".
#pragma once

#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/core/image.h"
#include "lf/core/splat_list.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/frame_merge.h"
#include "lf/job/merge.h"
#include "lf/job/task_assignment.h"
#include "lf/job/task_status.h"
#include "lf/job/worker_status.h"
#include "server/job_state_machine.h"
#include "server/job_store.h"
#include "server/lease_timeouts.h"
#include "server/metrics.h"
#include "server/radiosity_solve.h"
#include "server/speculation.h"
#include "server/sweep_task_numbering.h"
#include "server/task_state_machine.h"
#include "server/worker_registry.h"

namespace lf {

struct SchedulerOptions {
    absl::Duration lease = absl::Seconds(10);  // a lease lasts this long past the last heartbeat
    int max_failures = 3;                      // counted failures of one task that fail its job
    // Near the end of a job (no task of it queued), an idle worker gets a second lease of a task
    // running longer than this and longer than twice the job's mean task time; the first result
    // wins (both are the same bits), so one slow worker does not hold the job.
    absl::Duration speculate_after = absl::Seconds(1);
    // How often workers heartbeat, told to them with each lease.
    absl::Duration heartbeat_interval = absl::Milliseconds(300);
    // Where each job's merged tiles are kept (lf/job/tile_store.h): the coordinator keeps them
    // in files, so that a job's memory does not grow with its image.
    TileStoreFactory tile_stores = MakeMemoryTileStore;
    // Jobs queued or running at once; a submission beyond is refused (ResourceExhausted).
    size_t max_active_jobs = 1000;
};

// Counted as the scheduler works; read by /metrics at any time, without the scheduler's lock.
struct SchedulerMetrics {
    Counter leases;         // leases handed out, second leases of stragglers included
    Counter task_failures;  // counted failures: expired leases, task errors, refused results
    // Per task done while leased: seconds from its lease to its accepted result (the render
    // and the result's transfer), as the server's clock measures them.
    Histogram task_seconds{{0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120, 300, 600, 1800, 3600}};
    // Tasks merged, and the samples they brought (pixels times samples per pixel of their camera
    // part), per minute of the last hour: the dashboard's throughput.
    MinuteCounts tasks_done;
    MinuteCounts samples_done;
};

// What is queued and running now, for /metrics.
struct SchedulerLoad {
    int jobs_queued = 0, jobs_running = 0;
    int64_t tasks_queued = 0, tasks_running = 0;  // across active jobs
    int workers_live = 0;                         // seen within a lease
    int workers_busy = 0;                         // live and holding a current lease
};

enum class FailureKind {
    kTaskError,       // counts toward max_failures
    kWorkerShutdown,  // the worker was told to stop: not the task's fault
};

class Scheduler {
  public:
    using Clock = std::function<absl::Time()>;
    Scheduler(
        SchedulerOptions options, JobStore& store, Clock clock = [] { return absl::Now(); });

    // Plans and queues the job; `spec` must be validated. Returns the job id once the job is in
    // the store (an error, and nothing queued, when the store cannot take it). A request id
    // seen before returns that submission's job. ResourceExhausted when max_active_jobs jobs are
    // queued or running.
    absl::StatusOr<std::string> Submit(const JobSpec& spec);

    // Takes up the jobs the store holds that have not ended, as a server restarting does: their
    // recorded task results are merged again and every other task is queued (leases do not
    // outlive the server; their workers' late results are still taken). Returns the jobs that
    // are fully rendered, whose result the caller writes and Finishes.
    absl::StatusOr<std::vector<std::string>> Recover();

    // The first queued task of the highest-priority, oldest job that this worker may take (a
    // task that failed here goes to a live worker it has not failed on, while there is one); when
    // none is queued, a straggler's task (see speculate_after). Waits until `wait_until` for one to
    // be queued (a long poll: an idle worker starts on a new job at once); nullopt when there is
    // nothing to do. `about`: what the worker says of itself, for Workers().
    std::optional<TaskAssignment> LeaseTask(const std::string& worker,
                                            absl::Time wait_until = absl::InfinitePast(),
                                            const WorkerDescription* about = nullptr);

    // Extends the lease. False means stop: the job was cancelled or the lease is gone.
    bool Heartbeat(const std::string& lease_id, const std::string& worker);

    // Merges a task's result and records it in the store before returning. The result is
    // accepted even from an expired lease as long as the task is not done (it is the same bits
    // whoever renders it); a duplicate is ignored. Refused: a lease this server never handed to
    // `worker` (FailedPrecondition), and a result of the wrong rectangle or sample count
    // (InvalidArgument; a current lease's task is then queued again as a counted failure).
    // `job_rendered` says the job is now fully rendered: the caller writes the result and calls
    // Finish. A frame method's task (lf/job/frame_plan.h) comes with `splats`, its splat list
    // (coalesced here), and `sums` its camera part (a 0x0 tile with the stats when it has none);
    // InvalidArgument for splats of a tile task, a frame task's result without them, another
    // frame's splats or the wrong camera part.
    struct Completion {
        std::string job_id;
        bool job_rendered = false;
    };
    absl::StatusOr<Completion> Complete(const std::string& lease_id, const std::string& worker,
                                        const TileSums& sums, SplatList* splats = nullptr);

    // A patch-group task's result, taken as Complete takes a tile's. When it completes its
    // sweep, `outcome` holds the next sweep's input or the solution: the caller stores it as a
    // blob and calls Publish. A solve that runs out of iterations fails the job.
    struct SweepCompletion {
        std::string job_id;
        std::optional<RadiositySolve::Outcome> outcome;
    };
    absl::StatusOr<SweepCompletion> CompleteSweep(const std::string& lease_id,
                                                  const std::string& worker,
                                                  const SweepChunkResult& result);
    // Queues the sweep that reads blob `hash`, or the display tiles when `converged`; fails the
    // job when the blob could not be stored.
    void Publish(const std::string& job_id, bool converged,
                 const absl::StatusOr<std::string>& hash);

    // Gives a leased task back. Ignored when the lease is no longer current.
    absl::Status Fail(const std::string& lease_id, const std::string& worker,
                      const std::string& reason, FailureKind kind);

    absl::StatusOr<JobRecord> Cancel(const std::string& job_id);

    // A queued or running job's new priority: its queued tasks are leased in the new order from
    // the next lease on. Returns the record once it is durable; FailedPrecondition for a job that
    // has ended, NotFound for one the store does not hold.
    absl::StatusOr<JobRecord> SetPriority(const std::string& job_id, int priority);

    // Re-queues the tasks whose lease ran out (each counts as a failure of the task), and
    // forgets the workers silent for a lease. Returns how many leases expired.
    int ExpireLeases();

    // Ends the sampling of adaptive jobs whose time limit has passed since they started: passes
    // not yet merged are dropped (leases of them hear "stop"), tiles keep their first pass.
    // Returns the jobs that are now fully rendered, whose result the caller writes and Finishes.
    std::vector<std::string> EnforceTimeLimits();

    // A rendered job's record and image, to write as its result, and for an adaptive job how its
    // sampling ended. The image is read from the job's tile store one tile at a time after the
    // lock is released: a preview of a running job may show one tile's newer result beside
    // another's older one, never half a tile.
    struct JobImage {
        JobRecord record;
        Image image;
        std::optional<AdaptiveReport> adaptive;
    };
    absl::StatusOr<JobImage> Snapshot(const std::string& job_id) const;

    // Ends a fully rendered job: succeeded with the result file, or failed with the error.
    void Finish(const std::string& job_id, const absl::StatusOr<std::string>& result_path);

    // Running jobs as they are now, ended ones from the store.
    absl::StatusOr<JobRecord> Get(const std::string& job_id) const;
    // The jobs the query selects from the store, running ones as they are now.
    absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query = {}) const;

    // The blobs the jobs held in memory read (queued, running, or ended and not yet recorded):
    // their scenes' files and the radiosity sweeps' inputs and solutions.
    std::set<std::string> BlobsInUse() const;

    // Blocks until some job changed after `version` was current, or `deadline`, or Shutdown.
    // Returns the version now.
    uint64_t WaitForChange(uint64_t version, absl::Time deadline);
    void Shutdown();  // wakes every WaitForChange for good

    // A queued or running job's tasks as they are now (TaskStatus::log_lines left 0: the logs
    // are not the scheduler's); nullopt for a job that is not queued or running.
    std::optional<std::vector<TaskStatus>> Tasks(const std::string& job_id) const;

    // Whom a lease belongs to, for the log lines that come with its heartbeats and results.
    struct LeaseHolder {
        std::string job_id;
        int task = 0;
        int attempt = 0;  // 1 for the task's first lease
        std::string worker;
    };
    // Where a lease id of this server points when `worker` holds it, current or not, while its
    // job is queued or running; nullopt otherwise (a made-up id, another worker's lease, a lease
    // from before a restart, or a job that has ended).
    std::optional<LeaseHolder> HolderOf(const std::string& lease_id, const std::string& worker);

    // Called with an ended job's tasks as they were when it ended, after the scheduler's lock is
    // released and the job's final record is durable (or logged as not recorded), so that they
    // can be kept once the job leaves memory. Set before the first job is submitted or recovered.
    using TasksEnded = std::function<void(const std::string& job_id, std::vector<TaskStatus>)>;
    void OnTasksEnded(TasksEnded callback) { tasks_ended_ = std::move(callback); }

    // Workers the scheduler keeps track of: the live ones, and silent ones not yet forgotten
    // (the timeout checker forgets them within a tick of a lease's silence).
    size_t workers_tracked() const;

    // The live workers by id (a worker silent for a lease is forgotten), each with the task it
    // holds a current lease of.
    std::vector<WorkerStatus> Workers();
    SchedulerLoad Load();
    const SchedulerMetrics& metrics() const { return metrics_; }

  private:
    // What a task's leases left behind; its state is in Job::states.
    struct Task {
        int attempts = 0;                  // leases handed out
        int failures = 0;                  // counted failures
        std::vector<std::string> holders;  // the worker of each lease, by attempt - 1
        std::set<int> live;    // attempts whose lease is current: two when one is speculative
        absl::Time leased_at;  // when it last left the queue
        absl::Time finished = absl::InfinitePast();  // its first result merged
        std::string last_error;                      // of its last counted failure
        std::set<std::string> failed_on;
    };
    struct Job {
        JobRecord record;
        // The tiles' tasks and their results: a fixed plan, or an adaptive one (`adaptive`, the
        // same object) whose passes are appended to the tasks as results ask for them.
        std::unique_ptr<TileMerger> merger;
        AdaptiveTilePlan* adaptive = nullptr;
        // Frame methods (UsesFramePlan): their frame passes and merged sums, instead of `merger`
        // (then null). The Task* helpers below answer for either.
        std::unique_ptr<FrameMerger> frame{};
        TaskStateMachine states{};
        std::vector<Task> tasks{};   // by index, as many as `states`
        uint64_t submit_ticket = 0;  // the store's, for a retry that comes before the commit
        SpeculationPolicy speculation{absl::ZeroDuration()};
        // Radiosity solved in sweeps: while `solve` is set, its patch-group tasks follow the
        // tiles (numbered by `sweeps`, set once the job solves in sweeps) and the tiles wait. A
        // chunk goes back to the worker that did it before, which keeps its form-factor rows; that
        // is soft state, so any worker may take a chunk whose owner is gone.
        std::unique_ptr<RadiositySolve> solve{};
        std::optional<SweepTaskNumbering> sweeps{};
        std::string sweep_input{};  // blob of the current sweep's input; "" in sweep 0
        std::string solution{};     // blob of the solution, once solved
        std::map<int, std::string> chunk_owner{};
    };
    struct LeaseRef {
        Job* job;
        int task;
        int attempt;
    };
    // A job that ended, while its final record is queued but not yet durable: readers find it
    // here until it is, then in the store.
    struct Ending {
        JobRecord record;
        uint64_t ticket = 0;
    };
    // The scheduler's lock. Jobs ended while it is held have their final record queued, not
    // durable; on release it waits for those writes with the lock released, so no fsync is ever
    // waited for under it, then moves the jobs from `ending_` to the store's care.
    class Locked {
      public:
        explicit Locked(Scheduler& scheduler);
        ~Locked();
        std::unique_lock<std::mutex> lock;

      private:
        // Waits for the ended jobs' records with the lock released.
        void SettleEnded();
        Scheduler& scheduler_;
    };

    // The job of an earlier submission with this request id held in memory, and the store
    // ticket to wait for.
    std::optional<std::pair<std::string, uint64_t>> FindRequestInMemory(
        const std::string& request_id) const;
    // The record of a job that ended and is not (or not yet) in the store.
    const JobRecord* EndedRecord(const std::string& job_id) const;
    std::optional<TaskAssignment> TryLease(const std::string& worker,
                                           const WorkerDescription* about);
    // The current lease each worker holds (the newest, should one hold two).
    std::map<std::string, LeaseRef> LeasesByWorker();
    // The sweep and chunk of a patch-group task; nullopt for a tile's.
    static std::optional<SweepTaskNumbering::SweepChunk> SweepChunkOf(const Job& job, int task);
    // The one way the scheduler moves a task or a job; an illegal move is a broken invariant.
    void MoveTask(Job& job, int task, TaskState to);
    void MoveJob(Job& job, JobState to);
    // The job's planned tasks, those merged, whether all are, and their stats: the tile merger's
    // or the frame merger's.
    static size_t TaskCount(const Job& job);
    static size_t TasksDone(const Job& job);
    static bool Rendered(const Job& job);
    static const RenderStats& StatsOf(const Job& job);
    // Pixels times samples per pixel of a task's camera part; 0 for a radiosity sweep's.
    static uint64_t TaskSamples(const Job& job, int task);
    // Grows the job to `count` tasks, the new ones waiting.
    static void Grow(Job& job, size_t count);
    // Queues what a job starts with: its tiles not yet done, or its solve's first sweep.
    void QueueStart(Job& job);
    void QueueSweep(Job& job);
    // A job with its tasks planned as its spec says: tiles (fixed or adaptive), or for a frame
    // method the frame passes local mode plans (lf::FramePlanSettingsOf); InvalidArgument when
    // they cannot be.
    absl::StatusOr<std::unique_ptr<Job>> NewJob(JobRecord record) const;
    // Queues a task the adaptive plan appended.
    void QueuePass(Job& job, const RenderTask& pass);
    // Drops an adaptive job's passes once its time limit has passed; true if dropping them
    // completed the job (so that it is reported once, here or by Complete).
    bool EnforceTimeLimit(Job& job, absl::Time now);
    // Whether `worker` may take queued task `task` now: a sweep task goes to its chunk's owner
    // while that worker lives, and a task that failed on `worker` waits for a live worker it has
    // not failed on, while there is one.
    bool MayTake(const Job& job, int task, const std::string& worker, absl::Time now) const;
    // The lease a result names, when `worker` holds it (FailedPrecondition otherwise).
    absl::StatusOr<LeaseRef> ResultLease(const std::string& lease_id, const std::string& worker,
                                         absl::Time now);
    // Refuses a result: the task goes back to the queue as a counted failure.
    absl::Status Refuse(const LeaseRef& ref, const std::string& lease_id, const std::string& worker,
                        const absl::Status& why);
    // The bookkeeping of a task's first accepted result.
    void MarkDone(Job& job, int task, absl::Time now);
    // A second lease of a task running too long in the job, or -1 (see SpeculationPolicy).
    int StragglerFor(const Job& job, const std::string& worker, absl::Time now) const;
    TaskAssignment Grant(Job& job, int task, const std::string& worker, absl::Time now);
    std::string LeaseId(const Job& job, int task, int attempt) const;
    // Where a lease id of this server points, whether or not the lease is still current; nullopt
    // for ids it never handed out (forged, or from before a restart).
    std::optional<LeaseRef> Resolve(const std::string& lease_id);
    static bool HeldBy(const LeaseRef& ref, const std::string& worker);
    static bool IsCurrent(const LeaseRef& ref);
    // Ends the lease; when no other lease of the task is live, puts the task back in the queue.
    // Counts a failure unless `counted` is false; fails the job at max_failures.
    void Requeue(const LeaseRef& ref, const std::string& reason, bool counted);
    void FailJob(Job& job, const std::string& error);
    // The job's tasks as Tasks() reports them.
    std::vector<TaskStatus> TaskStatuses(const Job& job, absl::Time now) const;
    // Ends the live state of a job moved to a final state: its final record is queued and the
    // job waits in `ending_` until Locked's release finds it durable. Returns that record.
    JobRecord EndJob(Job& job);
    uint64_t Save(Job& job);  // queues the record's write and wakes watchers; a store ticket

    const SchedulerOptions options_;
    JobStore& store_;
    const Clock clock_;

    mutable std::mutex mutex_;
    std::condition_variable changed_;
    uint64_t version_ = 0;
    bool shutdown_ = false;
    uint64_t next_seq_ = 1;
    // In lease ids, so that a lease of an earlier run of the server is never taken for a current
    // one: attempts are counted from zero again after a restart.
    const std::string boot_;
    std::map<std::string, std::unique_ptr<Job>> active_;
    std::map<std::string, Ending> ending_;
    std::vector<std::string> to_settle_;           // in `ending_`, not yet waited for
    std::map<std::string, JobRecord> unrecorded_;  // ended while the store could not write
    // Ended jobs' tasks, for tasks_ended_ once the lock is released.
    std::vector<std::pair<std::string, std::vector<TaskStatus>>> ended_tasks_;
    TasksEnded tasks_ended_;
    LeaseTimeouts timeouts_;
    WorkerRegistry workers_;
    SchedulerMetrics metrics_;
};

}  // namespace lf
