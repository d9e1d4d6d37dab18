// Runs a job's execution (lf/job/job_execution.h) on threads, as the farm's workers would run
// its tasks: the tasks it starts with, then those its merges append, least QueueRank first, at
// most `threads` at once in one TBB arena (a task may parallel_for inside it). Results merge
// under one lock; exact sums make their order irrelevant to the bits. The time limit is read
// from `clock`, after every merge and at its deadline; a task it drops is cancelled if under
// way and its result ignored.
#pragma once

#include <atomic>
#include <functional>

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "lf/job/job_execution.h"

namespace lf {

using RunClock = std::function<absl::Time()>;

// Renders the task `lease` describes (JobExecution::Lease, taken under the lock) into whatever
// its kind returns, and merges that with `merge` once done; `cancel` is set when the time limit
// drops the task.
using RunTask =
    std::function<absl::Status(const TaskAssignment& lease, const std::atomic<bool>& cancel,
                               const std::function<absl::Status(const TaskResult&)>& merge)>;

struct RunOptions {
    int threads = 0;  // 0: all cores
    RunClock clock;   // empty: absl::Now
    // Called under the lock after every merge.
    std::function<void()> merged;
    // Set from anywhere (a signal handler: Ctrl-C) to stop: no task starts any more, those under
    // way are cancelled and their results dropped, so the execution keeps whole tasks only.
    // Polled every 50 ms. Null: never.
    const std::atomic<bool>* interrupt = nullptr;
};

// Runs until the execution is complete, interrupted (OK, with what was merged), or the first
// error; `started` is when its time limit counts from.
absl::Status RunExecution(JobExecution& execution, const RunTask& run, const RunOptions& options,
                          absl::Time started);

}  // namespace lf
