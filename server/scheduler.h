// The farm's task state machine, without I/O or gRPC: jobs are planned into tasks, tasks are
// leased to workers by job priority then age, leases live while heartbeats extend them, and
// results merge into the job's image.
//
// Task states: queued -> leased -> done. A lease that expires or a failure puts the task back
// in the queue, where other workers take it first; the third counted failure fails the job.
// Cancelling a job drops all its tasks at once: their heartbeats answer "stop".
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
#include "server/job_store.h"
#include "server/lease_timeouts.h"
#include "server/merge.h"

namespace lf {

struct SchedulerOptions {
    absl::Duration lease = absl::Seconds(10);  // a lease lasts this long past the last heartbeat
    int max_failures = 3;                      // counted failures of one task that fail its job
};

struct Lease {
    std::string id;
    std::string job_id;
    RenderTask task;
    JobSpec spec;
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
    // the store (an error, and nothing queued, when the store cannot take it).
    absl::StatusOr<std::string> Submit(const JobSpec& spec);

    // Takes up the jobs the store holds that have not ended, as a server restarting does: their
    // recorded task results are merged again and every other task is queued (leases do not
    // outlive the server; their workers' late results are still taken). Returns the jobs that
    // are fully rendered, whose result the caller writes and Finishes.
    absl::StatusOr<std::vector<std::string>> Recover();

    // The first queued task of the highest-priority, oldest job, preferring tasks that have not
    // failed on this worker. Waits until `wait_until` for one to be queued (a long poll: an
    // idle worker starts on a new job at once); nullopt when there is nothing to do.
    std::optional<Lease> LeaseTask(const std::string& worker,
                                   absl::Time wait_until = absl::InfinitePast());

    // Extends the lease. False means stop: the job was cancelled or the lease is gone.
    bool Heartbeat(const std::string& lease_id, const std::string& worker);

    // Merges a task's result and records it in the store before returning. The result is
    // accepted even from an expired lease as long as the task is not done (it is the same bits
    // whoever renders it); a duplicate is ignored.
    // `job_rendered` says the job is now fully rendered: the caller writes the result and calls
    // Finish.
    struct Completion {
        std::string job_id;
        bool job_rendered = false;
    };
    absl::StatusOr<Completion> Complete(const std::string& lease_id, const std::string& worker,
                                        const TileSums& sums);

    // Gives a leased task back. Ignored when the lease is no longer current.
    absl::Status Fail(const std::string& lease_id, const std::string& worker,
                      const std::string& reason, FailureKind kind);

    absl::StatusOr<JobRecord> Cancel(const std::string& job_id);

    // Re-queues the tasks whose lease ran out (each counts as a failure of the task). Returns
    // how many.
    int ExpireLeases();

    // A rendered job's record and image, to write as its result.
    absl::StatusOr<std::pair<JobRecord, Image>> Snapshot(const std::string& job_id) const;

    // Ends a fully rendered job: succeeded with the result file, or failed with the error.
    void Finish(const std::string& job_id, const absl::StatusOr<std::string>& result_path);

    absl::StatusOr<JobRecord> Get(const std::string& job_id) const { return store_.Get(job_id); }
    std::vector<JobRecord> List() const { return store_.List(); }

    // Blocks until some job changed after `version` was current, or `deadline`, or Shutdown.
    // Returns the version now.
    uint64_t WaitForChange(uint64_t version, absl::Time deadline);
    void Shutdown();  // wakes every WaitForChange for good

private:
    enum class TaskState { kQueued, kLeased, kDone };
    struct Task {
        TaskState state = TaskState::kQueued;
        int attempts = 0;  // leases handed out
        int failures = 0;  // counted failures
        std::string lease_id, worker;
        std::set<std::string> failed_on;
    };
    struct Job {
        JobRecord record;
        std::vector<RenderTask> plan;
        std::vector<Task> tasks;
        std::set<int> queued;
        RenderMerger merger;
    };
    struct LeaseRef {
        Job* job;
        int task;
    };

    std::optional<Lease> TryLease(const std::string& worker);
    // Where a lease id points, whether or not the lease is still current.
    std::optional<LeaseRef> Resolve(const std::string& lease_id);
    bool IsCurrent(const LeaseRef& ref, const std::string& lease_id) const;
    // Puts a leased task back in the queue, counting a failure unless `counted` is false; fails
    // the job at max_failures.
    void Requeue(Job& job, int task, const std::string& reason, bool counted);
    void FailJob(Job& job, const std::string& error);
    void EndJob(Job& job);  // drops the live state of a job in a final state
    absl::Status Save(Job& job);  // writes the record (the error is logged) and wakes watchers
    bool OtherWorkersAlive(const std::string& worker, absl::Time now) const;

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
    LeaseTimeouts timeouts_;
    std::map<std::string, absl::Time> workers_seen_;
};

}  // namespace lf
