// A job as the scheduler holds it while it is queued or running: its record, its execution (the
// kind-specific plan and merge, lf/job/job_execution.h), its tasks' states (TaskStateMachine,
// the one place they move) and what each task's leases left behind. Leases themselves, and who
// holds them, are the LeaseTable's.
#pragma once

#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/job/job_execution.h"
#include "lf/job/job_record.h"
#include "lf/job/task_status.h"
#include "lf/job/tile_store.h"
#include "lf/server/lease_table.h"
#include "lf/server/speculation.h"
#include "lf/server/task_state_machine.h"

namespace lf {

struct ScheduledJob {
    // What a task's leases left behind.
    struct Task {
        int attempts = 0;                            // leases handed out
        int failures = 0;                            // counted failures
        absl::Time leased_at;                        // when it last left the queue
        absl::Time finished = absl::InfinitePast();  // its first result merged
        std::string last_error;                      // of its last counted failure
        std::set<std::string> failed_on;
        // The holder of its last lease as recorded before a restart: the lease table, which
        // knows the holders of this run's leases, starts empty.
        std::string recorded_worker;
        TaskTimes times;           // of its merged result
        std::optional<int> frame;  // of a shot's task of one frame
    };

    // The job with its tasks planned as its spec says (MakeJobExecution); InvalidArgument when
    // they cannot be.
    static absl::StatusOr<std::unique_ptr<ScheduledJob>> Make(JobRecord record,
                                                              const TileStoreFactory& tile_stores,
                                                              absl::Duration speculate_after);

    // The one way a task moves, and the job; an illegal move is a broken invariant.
    void Move(int task, TaskState to);
    void MoveTo(absl::Time now, JobState to);
    // Grows to the execution's tasks and queues those of `tasks` that wait.
    void Queue(const std::vector<int>& tasks);
    // The record's counts and stats from the execution and the task states.
    void Sync();
    // The job's tasks as Scheduler::Tasks reports them.
    std::vector<TaskStatus> Statuses(const LeaseTable& leases, absl::Time now) const;
    // A done task's history, recorded with its result; Restore takes it back after a restart.
    TaskHistory History(int task, const LeaseTable& leases) const;
    void Restore(int task, const TaskHistory& history);
    // Adds a merged result's times (lf::TaskResult::times) to the task, the job and its frames.
    void AddTimes(int task, const TaskResult& result);
    const std::string& id() const { return record.id; }

    JobRecord record;
    std::unique_ptr<JobExecution> execution;
    TaskStateMachine states;
    std::vector<Task> tasks;     // by index, as many as `states`
    uint64_t submit_ticket = 0;  // the store's, for a retry that comes before the commit
    uint64_t run = 0;            // Scheduler::JobRun::run, set when it is queued
    SpeculationPolicy speculation{absl::ZeroDuration()};

  private:
    // The holder of the task's last lease, of this run or recorded before.
    std::string WorkerOf(int task, const LeaseTable& leases) const;
};

}  // namespace lf
