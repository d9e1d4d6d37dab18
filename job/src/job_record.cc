#include "lf/job/job_record.h"

#include "absl/strings/str_cat.h"
#include "lf/job/shot.h"

namespace lf {

const char* JobStateName(JobState state) {
    switch (state) {
        case JobState::kQueued:
            return "queued";
        case JobState::kRunning:
            return "running";
        case JobState::kSucceeded:
            return "succeeded";
        case JobState::kFailed:
            return "failed";
        case JobState::kCancelled:
            return "cancelled";
    }
    return "unknown";
}

absl::StatusOr<JobState> JobStateFromName(std::string_view name) {
    for (JobState s : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded,
                       JobState::kFailed, JobState::kCancelled}) {
        if (name == JobStateName(s)) return s;
    }
    return absl::InvalidArgumentError(
        absl::StrCat("unknown job state \"", std::string(name),
                     "\": expected queued, running, succeeded, failed or cancelled"));
}

int JobRecord::frames_done() const {
    int done = 0;
    for (const FrameProgress& frame : frames) done += frame.done;
    return done;
}

const FrameProgress* FrameOf(const JobRecord& job, int frame) {
    if (!job.spec.shot.frames || !job.spec.shot.frames->Contains(frame)) return nullptr;
    const size_t i = size_t(job.spec.shot.frames->IndexOf(frame));
    return i < job.frames.size() && job.frames[i].frame == frame ? &job.frames[i] : nullptr;
}

absl::Status CheckRendersFrame(const JobRecord& job, int frame) {
    if (job.spec.shot.frames && job.spec.shot.frames->Contains(frame)) return absl::OkStatus();
    return absl::NotFoundError(absl::StrCat(
        "job ", job.id, " renders no frame ", frame,
        job.spec.shot.frames
            ? absl::StrCat(" (its frames: ", FrameRangeText(*job.spec.shot.frames), ")")
            : std::string(" (a still)")));
}

std::vector<WorkerFailures> JobRecord::Blocklisted() const {
    std::vector<WorkerFailures> blocked;
    for (const WorkerFailures& w : worker_failures) {
        if (w.failures >= spec.blocklist_after) blocked.push_back(w);
    }
    return blocked;
}

}  // namespace lf
