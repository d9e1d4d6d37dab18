// Issue 30's blocklist, after Flamenco's: a worker that fails JobSpec::blocklist_after tasks of
// a job gets none of its tasks any more (Scheduler::LeaseTask skips the job for it), so that one
// broken worker (a missing GPU driver, a full disk) does not use up every task's attempts. The
// counts are the job record's (JobRecord::worker_failures), saved with it, so they outlive a
// restart. Only failures a worker reports count (task errors, refused results): an expired lease
// is a dead or cut-off worker, whose next run has a new id anyway.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "lf/job/job_record.h"

namespace lf {

// Counts a failure of a task of `job` that `worker` reported; true when it blocklists the worker.
bool CountWorkerFailure(JobRecord& job, const std::string& worker, const std::string& error);

bool IsBlocklisted(const JobRecord& job, const std::string& worker);

// "w1 (3 failures, last: out of memory), w2 (...)", as `lightfarm status` prints it.
std::string BlocklistText(const std::vector<WorkerFailures>& blocked);

// Why the job must fail when every one of the `live` workers is blocklisted from it (it would
// wait for ever otherwise); nullopt while one of them may take its tasks, or none is live (the
// job waits for workers as any job does).
std::optional<std::string> StrandedError(const JobRecord& job,
                                         const std::vector<std::string>& live);

}  // namespace lf
