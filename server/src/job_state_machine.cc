#include "lf/server/job_state_machine.h"

#include "absl/strings/str_cat.h"

namespace lf {

bool IsLegalJobTransition(JobState from, JobState to) {
    switch (from) {
        case JobState::kQueued:
            return to != JobState::kQueued && to != JobState::kSucceeded;
        case JobState::kRunning:
            return IsFinal(to);
        default:
            return false;
    }
}

absl::Status TransitionJob(JobRecord& job, JobState to, absl::Time now) {
    if (!IsLegalJobTransition(job.state, to)) {
        return absl::FailedPreconditionError(absl::StrCat("job ", job.id, ": no transition from ",
                                                          JobStateName(job.state), " to ",
                                                          JobStateName(to)));
    }
    if (to == JobState::kRunning) job.started = now;
    if (IsFinal(to)) job.finished = now;
    job.state = to;
    return absl::OkStatus();
}

absl::Status ReopenJob(JobRecord& job, bool succeeded_too) {
    const bool succeeded = job.state == JobState::kSucceeded;
    if (job.state != JobState::kFailed && job.state != JobState::kCancelled &&
        !(succeeded && succeeded_too)) {
        return absl::FailedPreconditionError(absl::StrCat(
            "job ", job.id, " is ", JobStateName(job.state),
            ": only a failed or cancelled job is queued again (a queued or running one has its "
            "failed tasks requeued; a succeeded shot has chosen frames rendered again with "
            "--frames)"));
    }
    job.state = JobState::kQueued;
    job.error.clear();
    job.result_path.clear();
    // It starts again at its next lease: an adaptive job's time limit counts from there.
    job.started = job.finished = absl::InfinitePast();
    job.paused_for = absl::ZeroDuration();
    return absl::OkStatus();
}

}  // namespace lf
