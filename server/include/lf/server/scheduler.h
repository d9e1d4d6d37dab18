// The farm's scheduler, without I/O or gRPC: what spans jobs. Jobs are queued by priority then
// age, their tasks leased to workers, leases live while heartbeats extend them, results go to
// the job, and the store keeps it all durable. Everything a kind of job does its own way (its
// plan, merge, task order, time limit: lf/job/job_execution.h) is its execution's to say. It
// composes small units, each tested alone: task states change only through TaskStateMachine,
// job states through TransitionJob; LeaseTable owns the leases, WorkerRegistry the live
// workers, SpeculationPolicy decides second leases; the timeout checker (TimeoutChecker) calls
// ExpireLeases and EnforceTimeLimits. The store is never read, nor waited for, under the
// scheduler's lock.
//
// A lease that expires or a failure puts the task back in the queue, where workers it has not
// failed on take it first; the job's max_attempts-th counted failure of a task fails the job. A
// worker that failed blocklist_after of a job's tasks gets none of them (lf/server/blocklist.h).
// Cancelling a job drops all its tasks at once: their heartbeats answer "stop".
#pragma once

#include <condition_variable>
#include <deque>
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
#include "lf/job/job_execution.h"
#include "lf/job/task_assignment.h"
#include "lf/job/task_status.h"
#include "lf/job/worker_status.h"
#include "lf/server/ended_jobs.h"
#include "lf/server/job_dependencies.h"
#include "lf/server/job_state_machine.h"
#include "lf/server/job_store.h"
#include "lf/server/lease_table.h"
#include "lf/server/metrics.h"
#include "lf/server/scheduled_job.h"
#include "lf/server/worker_registry.h"

namespace lf {

struct SchedulerOptions {
    absl::Duration lease = absl::Seconds(10);  // a lease lasts this long past the last heartbeat
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
    // Current leases of all the workers of one token (lf::PrincipalOf their ids) at once: a token
    // leasing under ever new worker ids holds no more of the farm's tasks than this.
    int max_leases_per_token = 256;
    // A worker whose leases expire unheard WorkerRegistry::kAbandonedInARow times in a row gets
    // no lease for this many leases' time.
    int quarantine_leases = 10;
    // A worker silent for a lease is listed as offline (Workers) until this long after it was
    // last seen (lightfarm-server --forget-workers-after).
    absl::Duration forget_workers_after = absl::Hours(1);
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
    kTaskError,       // counts toward the job's max_attempts and the worker's blocklist
    kWorkerShutdown,  // the worker was told to stop: not the task's fault
};

class Scheduler {
  public:
    using Clock = std::function<absl::Time()>;
    Scheduler(
        SchedulerOptions options, JobStore& store, Clock clock = [] { return absl::Now(); });

    // One run of a job: a job requeued after it ended runs again under a new number, so that
    // what the caller does for an earlier run (writing its image, awaiting its last record)
    // cannot end the new one. Numbers are this process's, never stored.
    struct JobRun {
        std::string job_id;
        uint64_t run = 0;
        auto operator<=>(const JobRun&) const = default;
    };

    // Plans and queues the job; `spec` must be validated, but for its dependencies (spec.after:
    // their ids as CheckDependencyIds checks them, each known and not failed nor cancelled, see
    // AddDependencies). Returns the job id once the job is in
    // the store (an error, and nothing queued, when the store cannot take it). A request id
    // seen before returns that submission's job. ResourceExhausted when max_active_jobs jobs are
    // queued or running.
    absl::StatusOr<std::string> Submit(const JobSpec& spec);

    // Takes up the jobs the store holds that have not ended, as a server restarting does: their
    // recorded task results are merged again and every other task is queued (leases do not
    // outlive the server; their workers' late results are still taken). Returns the jobs that
    // are fully rendered, whose result the caller writes and Finishes.
    absl::StatusOr<std::vector<JobRun>> Recover();

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

    // Merges a task's result (lf::TaskResult: what the task's kind returns), and records it in
    // the store before returning when the job's execution keeps it. The result is accepted even
    // from an expired lease as long as the task is not done (it is the same bits whoever renders
    // it); a duplicate is ignored. Refused: a lease this server never handed to `worker`
    // (FailedPrecondition), and a result that is not the task's (InvalidArgument, from the
    // execution; a current lease's task is then queued again as a counted failure).
    // `job_rendered` says the job is now fully rendered: the caller writes the result and calls
    // Finish. When a patch-group task completes its sweep, `sweep` holds the next sweep's input
    // or the solution: the caller stores it as a blob and calls Publish. A solve that runs out of
    // iterations fails the job.
    // `frames_completed`: a shot's frames the result completed, whose EXR the caller writes
    // (WriteFrame) before it learns the job is rendered.
    // The result of the task that renders the job (`job_rendered`) is not waited for: its record
    // becomes durable while the caller writes the job's image, and the caller calls
    // AwaitRecorded before the worker hears "done".
    struct Completion {
        std::string job_id;
        uint64_t run = 0;  // JobRun::run of the job that merged the result
        bool job_rendered = false;
        std::optional<RadiositySolve::Outcome> sweep;
        std::vector<int> frames_completed;
        struct Unrecorded {
            int task = 0;
            uint64_t ticket = 0;
        };
        std::optional<Unrecorded> unrecorded;
    };
    absl::StatusOr<Completion> Complete(const std::string& lease_id, const std::string& worker,
                                        const TaskResult& result);
    // Waits for a completion's record (Completion::unrecorded; none: at once). A record that
    // could not be stored fails the job while it still runs (a restart would lack the result),
    // so the caller awaits it before Finish; the error is the worker's answer.
    absl::Status AwaitRecorded(const Completion& completion);
    // A tile's result, or a splat task's (`sums` its camera part, a 0x0 tile with the stats when
    // it has none, and `splats` its splat list).
    absl::StatusOr<Completion> Complete(const std::string& lease_id, const std::string& worker,
                                        const TileSums& sums, SplatList* splats = nullptr) {
        return Complete(lease_id, worker, TaskResult{.sums = &sums, .splats = splats});
    }
    absl::StatusOr<Completion> CompleteSweep(const std::string& lease_id, const std::string& worker,
                                             const SweepChunkResult& result) {
        return Complete(lease_id, worker, TaskResult{.sweeps = {&result, 1}});
    }
    // Queues the sweep that reads blob `hash` (not stored when its `bytes` go with the leases,
    // JobExecution::Publish), or the display tiles when `converged`; fails the job when the
    // blob could not be stored.
    void Publish(const std::string& job_id, bool converged, const absl::StatusOr<std::string>& hash,
                 std::shared_ptr<const std::string> bytes = nullptr);

    // Gives a leased task back. Ignored when the lease is no longer current.
    absl::Status Fail(const std::string& lease_id, const std::string& worker,
                      const std::string& reason, FailureKind kind);

    absl::StatusOr<JobRecord> Cancel(const std::string& job_id);

    // A queued or running job's new priority: its queued tasks are leased in the new order from
    // the next lease on. Returns the record once it is durable; FailedPrecondition for a job that
    // has ended, NotFound for one the store does not hold.
    absl::StatusOr<JobRecord> SetPriority(const std::string& job_id, int priority);

    // Job management (issue 30).
    // `lightfarm requeue`: the job's failed tasks go back in the queue with their failures
    // reset (their lease counts stay, as the attempt numbers of their logs), and its blocklist
    // is cleared. A failed or cancelled job is queued again (ReopenJob): its recorded task
    // results merge as after a restart (Recover) and it renders on from there. `rendered`: the
    // job is fully rendered already; the caller writes the result and Finishes. NotFound for a
    // job the store does not hold, FailedPrecondition for a succeeded one, Unavailable for one
    // ending right now (its final record not yet durable).
    struct Requeued {
        JobRecord record;
        uint64_t run = 0;  // JobRun::run of the job queued again
        bool rendered = false;
        std::vector<int> frames;  // RequeueFrames: the frames whose EXRs are dropped
    };
    absl::StatusOr<Requeued> RequeueJob(const std::string& job_id);
    // `lightfarm requeue --frames`: frames `frames` of an ended shot (a succeeded one too) are
    // rendered again from scratch: the results of their tasks are removed from the store with
    // the reopened record, and their EXRs are no longer recorded (Requeued::frames: those, and
    // the other frames of a chunk that holds one); the rest merges as after a restart and the
    // job is queued. InvalidArgument naming them for a still or frames outside the shot,
    // FailedPrecondition for a job not ended, or an adaptive shot; else as RequeueJob.
    // `remove_files(frames)` is called once the job is queued again, before a worker can lease
    // it, so that a frame rendered again at once is never removed as the old one.
    using RemoveFrameFiles = std::function<void(const std::vector<int>& frames)>;
    absl::StatusOr<Requeued> RequeueFrames(const std::string& job_id, const FrameRange& frames,
                                           const RemoveFrameFiles& remove_files);
    // `lightfarm pause` and `resume` (JobRecord::paused): returns the record once durable;
    // FailedPrecondition for a job that has ended, NotFound for one the store does not hold.
    absl::StatusOr<JobRecord> SetPaused(const std::string& job_id, bool paused);

    // Dependencies (issue 30, lf/server/job_dependencies.h). A job leases nothing while a job of
    // its spec.after is queued or running, and fails when one ends without succeeding (and so
    // on down a chain); a dependency deleted since counts as settled. `lightfarm depend`: the
    // queued job also runs after `after` (ids checked by CheckDependencyIds); returns the record
    // once durable. NotFound for an unknown job or dependency, FailedPrecondition for a job that is
    // not queued, a dependency that failed or was cancelled, or a cycle (its CycleText).
    absl::StatusOr<JobRecord> AddDependencies(const std::string& job_id,
                                              const std::vector<std::string>& after);

    // Re-queues the tasks whose lease ran out (each counts as a failure of the task), and
    // forgets the workers silent for a lease. Returns how many leases expired.
    int ExpireLeases();

    // Ends the sampling of adaptive jobs whose time limit has passed since they started: passes
    // not yet merged are dropped (leases of them hear "stop"), tiles keep their first pass.
    // Returns the jobs that are now fully rendered, whose result the caller writes and Finishes.
    std::vector<JobRun> EnforceTimeLimits();

    // A rendered job's record and image, to write as its result, and for an adaptive job how its
    // sampling ended. The image is read from the job's tile store one tile at a time after the
    // lock is released: a preview of a running job may show one tile's newer result beside
    // another's older one, never half a tile.
    struct JobImage {
        JobRecord record;
        uint64_t run = 0;  // JobRun::run of the job read
        Image image;
        std::optional<AdaptiveReport> adaptive;
    };
    absl::StatusOr<JobImage> Snapshot(const std::string& job_id) const;
    // A running shot's frame `frame` as Snapshot reads a job: the record's spec is the frame's
    // (FrameSpec), its stats the frame's. NotFound for a frame the job does not render.
    absl::StatusOr<JobImage> FrameSnapshot(const std::string& job_id, int frame) const;
    // Records frame `frame`'s EXR as written (fetchable from now on, whatever the job ends as), or
    // fails the job with the error. False, and nothing done, when that run has ended.
    bool FrameWritten(const JobRun& run, int frame, const absl::StatusOr<std::string>& path);
    // The frames of running shots that are complete but whose EXR is not recorded (the
    // coordinator stopped between the merge and the write).
    std::vector<std::pair<JobRun, int>> UnwrittenFrames() const;
    // The run of queued or running job `job_id`; nullopt for any other.
    std::optional<uint64_t> RunOf(const std::string& job_id) const;

    // Ends a fully rendered job: succeeded with the result file, or failed with the error.
    // Nothing when that run has ended (a job cancelled meanwhile, or cancelled and requeued).
    void Finish(const JobRun& rendered, const absl::StatusOr<std::string>& result_path);

    // Running jobs as they are now, ended ones from the store.
    absl::StatusOr<JobRecord> Get(const std::string& job_id) const;
    // Get for a reader that a client may act on at once (WatchJob): nullopt while the job has
    // ended but its end has not settled (see WaitForEnd), rather than an end that a `requeue`
    // would still refuse.
    absl::StatusOr<std::optional<JobRecord>> GetSettled(const std::string& job_id) const;
    // The jobs the query selects from the store, running ones as they are now.
    absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query = {}) const;

    // The blobs the jobs held in memory read (queued, running, or ended and not yet recorded):
    // their scenes' files and the radiosity sweeps' inputs and solutions.
    std::set<std::string> BlobsInUse() const;

    // Blocks until some job changed after `version` was current, or `deadline`, or Shutdown.
    // Returns the version now.
    uint64_t WaitForChange(uint64_t version, absl::Time deadline);
    // What WaitForEnd saw when it returned.
    enum class EndWait {
        // The job is not queued or running and its end is settled: its final record is durable
        // in the store, so a client told of the end finds the job there, for a `requeue` or a
        // `list` at once (or the write failed and was logged: then neither finds it). An
        // unknown job counts as ended.
        kEnded,
        kRunning,   // `deadline` came first: the job is queued, running, or its end not settled
        kShutdown,  // Shutdown was called, and the job is queued or running
    };
    // Blocks until the job has ended and its end is settled, or `deadline`, or Shutdown. WatchJob
    // paces its messages with it, so that a job's end goes out as soon as it settled.
    EndWait WaitForEnd(const std::string& job_id, absl::Time deadline);
    void Shutdown();  // wakes every WaitForChange and WaitForEnd for good

    // A queued or running job's tasks as they are now (TaskStatus::log_lines left 0: the logs
    // are not the scheduler's); nullopt for a job that is not queued or running.
    std::optional<std::vector<TaskStatus>> Tasks(const std::string& job_id) const;

    // Whom a lease belongs to, for the log lines that come with its heartbeats and results.
    struct LeaseHolder {
        std::string job_id;
        int task = 0;
        int attempt = 0;  // 1 for the task's first lease
        std::string worker;
        bool current = false;  // false once the lease ended (failed, expired, done, cancelled)
        size_t parts = 0;      // parts its result must hold (JobExecution::ResultParts)
    };
    // Where a lease id of this server points when `worker` holds it, current or not, while its
    // job is queued or running; nullopt otherwise (a made-up id, another worker's lease, a lease
    // from before a restart, or a job that has ended).
    std::optional<LeaseHolder> HolderOf(const std::string& lease_id, const std::string& worker);

    // Called with an ended job's final record and its tasks as they were when it ended, after
    // the scheduler's lock is released and that record is durable (or logged as not recorded),
    // so that they can be kept once the job leaves memory; before the end settles (WaitForEnd),
    // so a client told of the end finds them kept. Until it returns the job cannot be requeued
    // (UNAVAILABLE: "again in a moment"); the record stays the one the job ended with when it
    // is requeued afterwards. Set before the first job is submitted or recovered.
    using TasksEnded = std::function<void(const JobRecord& ended, std::vector<TaskStatus>)>;
    void OnTasksEnded(TasksEnded callback) { tasks_ended_ = std::move(callback); }

    // Workers the scheduler keeps track of: the live ones, and silent ones not yet forgotten
    // (the timeout checker forgets them within a tick of a lease's silence).
    size_t workers_tracked() const;

    // The live workers by id (a worker silent for a lease is forgotten), each with the task it
    // holds a current lease of.
    std::vector<WorkerStatus> Workers();
    SchedulerLoad Load();

    // Worker control (lightfarm workers enable|disable|drain), kept by worker name: the name a
    // worker known now (live or offline) goes by when `name_or_id` is its id or its name, or a
    // name with a control set before; nullopt otherwise. A worker without a name is kept by id.
    std::optional<std::string> WorkerKey(const std::string& name_or_id);
    // Sets the control of the workers named `key` (a WorkerKey): those disabled or draining
    // lease nothing new from now on; a task they hold runs to its end.
    void SetWorkerControl(const std::string& key, WorkerControl control);
    const SchedulerMetrics& metrics() const { return metrics_; }

  private:
    using Job = ScheduledJob;
    // A lease this server handed out, and its job, while that job is queued or running.
    struct LeaseRef {
        Job* job;
        const Lease* lease;
        std::string id;
    };
    // The scheduler's lock. Jobs ended while it is held have their final record queued, not
    // durable; on release it waits for those writes with the lock released, so no fsync is ever
    // waited for under it, then leaves the jobs to the store's care.
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

    // The job of an earlier submission with this request id, in the store or in memory, and the
    // store ticket to wait for. Called and returns with `locked` held; reads the store without.
    absl::StatusOr<std::optional<std::pair<std::string, uint64_t>>> FindRequest(
        const std::string& request_id, Locked& locked);
    // The job of an earlier submission with this request id held in memory, and the store
    // ticket to wait for.
    std::optional<std::pair<std::string, uint64_t>> FindRequestInMemory(
        const std::string& request_id) const;
    // Takes up a job of the store that has not ended, as Recover does: its recorded results
    // merge again in the order they merged, every other task is queued. In active_ after;
    // returns whether it is fully rendered.
    absl::StatusOr<bool> TakeUp(JobRecord record,
                                const std::map<int, JobStore::RecordedTask>& results);
    // The same with the job planned already (Job::Make).
    absl::StatusOr<bool> TakeUp(std::unique_ptr<Job> job,
                                const std::map<int, JobStore::RecordedTask>& results);
    std::optional<TaskAssignment> TryLease(const std::string& worker,
                                           const WorkerDescription* about);
    // Drops a job's tasks once its time limit has passed; true if dropping them completed the
    // job (so that it is reported once, here or by Complete).
    bool EnforceTimeLimit(Job& job, absl::Time now);
    // ResourceExhausted when max_active_jobs jobs are queued or running (`action`: what to try
    // again). Called under the lock.
    absl::Status CheckActiveJobLimit(const char* action) const;
    // An ended job taken up again from the store (RequeueJob; RequeueFrames with `frames`).
    absl::StatusOr<Requeued> Reopen(const std::string& job_id, const RemoveFrameFiles& remove_files,
                                    const std::optional<FrameRange>& frames);
    // Whether `worker` may take queued task `task` now: a task the execution prefers for another
    // live worker waits for it, and a task that failed on `worker` waits for a live worker it has
    // not failed on, while there is one.
    bool MayTake(const Job& job, int task, const std::string& worker, absl::Time now) const;
    // Whether worker `id` may lease the job's tasks: enabled, not blocklisted from it, with its
    // tags.
    bool MayWorkOn(const Job& job, const std::string& id, const WorkerDescription& about) const;
    // Whether the execution's preferred worker for task `t` (lf::JobExecution::PreferredWorker)
    // lives and may lease it now (MayWorkOn, and not quarantined): the task waits for it, and
    // another worker's result of it takes its place (TaskResult::takes_over).
    bool PreferredMayTake(const Job& job, int t, absl::Time now) const;
    // Whether the job goes to `worker`, which has `tags`: the worker has every tag of the job,
    // and the job's max_workers cap leaves it room (or the worker already holds a lease of it).
    bool Admits(const Job& job, const std::string& worker,
                const std::vector<std::string>& tags) const;
    // Whether a job of the job's spec.after is still queued or running.
    bool WaitsForDependency(const Job& job) const;
    // The states of jobs `ids`, from memory or the store (read with the lock released, as
    // FindRequest does); Called and returns with `locked` held. A store error other than
    // NotFound is returned.
    absl::StatusOr<std::map<std::string, DependencyState>> DependencyStates(
        const std::vector<std::string>& ids, Locked& locked);
    // Fails the job when a job it runs after, not held in memory, ended without succeeding by
    // `known` (Recover's and RequeueJob's view of the store); true if it did.
    bool FailIfDependencyEnded(Job& job, const std::map<std::string, DependencyState>& known);
    // Why `job` cannot run, when a job it runs after, not held in memory, ended without
    // succeeding by `known`; nullopt when none did.
    std::optional<std::string> EndedDependencyFailure(
        const JobRecord& job, const std::map<std::string, DependencyState>& known) const;
    // Get, and GetSettled when `settled_only`.
    absl::StatusOr<std::optional<JobRecord>> Read(const std::string& job_id,
                                                  bool settled_only) const;
    // The job's record as a reader sees it: with its waiting_reason.
    JobRecord ReadRecord(const Job& job, absl::Time now) const;
    // The lease a result names, when `worker` holds it (FailedPrecondition otherwise).
    absl::StatusOr<LeaseRef> ResultLease(const std::string& lease_id, const std::string& worker,
                                         absl::Time now);
    // Refuses a result: the task goes back to the queue as a counted failure.
    absl::Status Refuse(const LeaseRef& ref, const std::string& worker, const absl::Status& why);
    // The bookkeeping of a task's first accepted result.
    void MarkDone(Job& job, int task, absl::Time now);
    // A second lease of a task running too long in the job, or -1 (see SpeculationPolicy).
    int StragglerFor(const Job& job, const std::string& worker, absl::Time now) const;
    TaskAssignment Grant(Job& job, int task, const std::string& worker, absl::Time now);
    // The lease and its job when `worker` holds it, current or not; nullopt otherwise (a
    // made-up id, another worker's lease, one from before a restart, or of a job that ended).
    std::optional<LeaseRef> Resolve(const std::string& lease_id, const std::string& worker);
    // Ends the lease; when no other lease of the task is current, puts the task back in the
    // queue. Counts a failure unless `counted` is false; fails the job at its max_attempts.
    void Requeue(const LeaseRef& ref, const std::string& reason, bool counted);
    // Requeue for a failure the worker itself reported (an error, a refused result): it also
    // counts toward the worker's blocklist, and fails the job when that leaves it no live worker.
    void RequeueReported(const LeaseRef& ref, const std::string& reason);
    // The queued or running job `job_id` to change, with `locked` held; for any other, the
    // status to answer (read from the store with the lock released, as SetPriority does).
    absl::StatusOr<Job*> ActiveJob(const std::string& job_id, Locked& locked);
    // Fails the job when every live worker is blocklisted from it (StrandedError).
    void FailIfStranded(Job& job);
    void FailJob(Job& job, const std::string& error);
    // A stored job Recover cannot take up, ended as failed with `why`; the lock is held.
    void FailUnrecoverable(JobRecord record, const absl::Status& why);
    // Ends the live state of a job moved to a final state: its final record is queued and the
    // job waits in `ended_` until Locked's release finds it durable. Returns that record.
    JobRecord EndJob(Job& job);
    // Queues the record's write (removing the results of tasks `drop_results` with it) and
    // wakes watchers; returns a store ticket.
    uint64_t Save(Job& job, const std::vector<int>& drop_results = {});
    // Wakes watchers to a change that is not written: a lease, a radiosity sweep's progress (a
    // restart queues the task again, and solves again from sweep 0). Writing the record for
    // each of them cost the coordinator about a fifth of its CPU on the Cornell box's
    // radiosity job (about 40 tasks, each leased and completed).
    void Announce(Job& job);

    const SchedulerOptions options_;
    JobStore& store_;
    const Clock clock_;

    mutable std::mutex mutex_;
    std::condition_variable changed_;
    // Notified when ended jobs settle, and at Shutdown: WaitForEnd's, apart from changed_, which
    // every lease and result notifies.
    std::condition_variable settled_;
    uint64_t version_ = 0;
    bool shutdown_ = false;
    uint64_t next_seq_ = 1;
    uint64_t next_run_ = 1;  // JobRun::run
    std::map<std::string, std::unique_ptr<Job>> active_;
    EndedJobs ended_;
    uint64_t left_memory_ = 0;  // ended jobs settled out of `ended_`, for FindRequest
    // Ended jobs' tasks, for tasks_ended_ once the lock is released.
    std::vector<std::pair<JobRecord, std::vector<TaskStatus>>> ended_tasks_;
    // Dependents to fail (job id, reason), worked through by the outermost EndJob.
    std::deque<std::pair<std::string, std::string>> failing_dependents_;
    bool failing_dependents_busy_ = false;
    TasksEnded tasks_ended_;
    LeaseTable leases_;
    WorkerRegistry workers_;
    std::map<std::string, WorkerControl> controls_;  // by WorkerKey; none: enabled
    // The control of the worker `id` described as `about`.
    WorkerControl ControlOf(const std::string& id, const WorkerDescription& about) const;
    SchedulerMetrics metrics_;
};

}  // namespace lf
