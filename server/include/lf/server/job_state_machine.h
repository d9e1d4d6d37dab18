// A job's state and the one function that changes it, stamping when it started and ended:
//
//   queued -> running -> succeeded | failed | cancelled
//      +-----------------------------^
//
// The final states have no way out but ReopenJob's (`lightfarm requeue`: failed or cancelled
// back to queued, and with --frames a succeeded shot too); a job may end without ever running
// (cancelled while queued, or failed when its store write or its plan fails).
#pragma once

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "lf/job/job_record.h"

namespace lf {

bool IsLegalJobTransition(JobState from, JobState to);

// Moves `job` to `to` at `now`: `started` is set on running, `finished` on ending.
// FailedPrecondition, and nothing changed, for a move the diagram does not allow.
absl::Status TransitionJob(JobRecord& job, JobState to, absl::Time now);

// Job management (issue 30): a failed or cancelled job queued again (lightfarm requeue), its
// error, start and end cleared; with `succeeded_too` (requeue --frames) a succeeded one also,
// its result path cleared. FailedPrecondition, and nothing changed, for any other state.
absl::Status ReopenJob(JobRecord& job, bool succeeded_too = false);

}  // namespace lf
