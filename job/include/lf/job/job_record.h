// A job as the coordinator reports and records it: its spec, its state and its progress.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/core/film.h"
#include "lf/job/job_spec.h"
#include "lf/job/task_status.h"

namespace lf {

enum class JobState { kQueued, kRunning, kSucceeded, kFailed, kCancelled };
const char* JobStateName(JobState state);
// The state named `name` (JobStateName's inverse); InvalidArgument for any other name.
absl::StatusOr<JobState> JobStateFromName(std::string_view name);
inline bool IsFinal(JobState s) { return s != JobState::kQueued && s != JobState::kRunning; }

// A worker's counted task failures in one job (issue 30's blocklist): those it reported itself
// (task errors and refused results), not leases that expired.
struct WorkerFailures {
    std::string worker;
    int failures = 0;
    std::string last_error;
};

struct JobRecord {
    std::string id;
    uint64_t seq = 0;  // submission order
    JobSpec spec;
    JobState state = JobState::kQueued;
    std::string error;
    std::string last_error;  // the most recent task failure's reason, while its task is retried
    absl::Time submitted, started = absl::InfinitePast(), finished = absl::InfinitePast();
    int tasks_total = 0, tasks_done = 0, tasks_running = 0, retries = 0;
    int tasks_leased = 0;  // leases ever handed out, across server restarts: renders started
    RenderStats stats;
    std::string result_path;  // the EXR, once succeeded
    // A shot's frames in frame order (none for a still); a frame's EXR stays fetchable whatever
    // the job ends as.
    std::vector<FrameProgress> frames;
    // Why a queued or running job has tasks no worker takes, when the scheduler knows ("waiting
    // for a worker with tags gpu"); set as the job is read, never stored.
    std::string waiting_reason;
    // Every worker that failed a task of this job, in the order of their first failure.
    std::vector<WorkerFailures> worker_failures;
    // `lightfarm pause`: a queued or running job that leases nothing new (its running tasks
    // finish and merge) until resumed. A flag, not a state: the job is still queued or running.
    bool paused = false;
    // The adaptive time limit's clock stops while the job is paused: the time paused since it
    // started, besides the current pause, which began at paused_at (InfinitePast when running).
    absl::Duration paused_for = absl::ZeroDuration();
    absl::Time paused_at = absl::InfinitePast();
    TaskTimes times;  // summed over its merged tasks (issue 30's history)
    // Dependencies (issue 30): of spec.after, those not ended yet while the job is queued; set
    // as the job is read, never stored.
    std::vector<std::string> waiting_for;
    int frames_done() const;
    // The workers of worker_failures with spec.blocklist_after failures or more: they get no
    // more tasks of this job.
    std::vector<WorkerFailures> Blocklisted() const;
};

// What a done task's leases left behind, recorded with its result so that `lightfarm tasks`
// still shows it after the coordinator restarts.
struct TaskHistory {
    int attempts = 0;                          // leases handed out
    int failures = 0;                          // counted failures
    std::string worker;                        // the holder of its last lease (TaskStatus::worker)
    absl::Time leased = absl::InfinitePast();  // when it last left the queue
    absl::Time finished = absl::InfinitePast();  // its result merged
    TaskTimes times;                             // as its worker measured them
    uint64_t samples = 0;                        // lf::JobExecution::TaskSamples
    std::optional<int> frame;                    // a shot's task of one frame (not a chunk)
};

// A shot's progress of `frame` (in frame order: at its position in the range); null when the job
// does not render it or its record does not list it yet (not synced with its execution).
const FrameProgress* FrameOf(const JobRecord& job, int frame);
// NotFound naming the frame and the job (and the frames it renders) when `job` does not render
// `frame`: what a fetch or the dashboard answers for it.
absl::Status CheckRendersFrame(const JobRecord& job, int frame);

}  // namespace lf
