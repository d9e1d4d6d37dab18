#include "lf/server/scheduled_job.h"

#include <cstdlib>

#include "lf/core/log.h"
#include "lf/server/job_state_machine.h"

namespace lf {

absl::StatusOr<std::unique_ptr<ScheduledJob>> ScheduledJob::Make(
    JobRecord record, const TileStoreFactory& tile_stores, absl::Duration speculate_after) {
    auto job = std::make_unique<ScheduledJob>();
    job->record = std::move(record);
    absl::StatusOr<std::unique_ptr<JobExecution>> execution =
        MakeJobExecution(job->record.spec, tile_stores);
    if (!execution.ok()) return execution.status();
    job->execution = std::move(*execution);
    job->speculation = SpeculationPolicy(speculate_after);
    job->Queue({});
    return job;
}

void ScheduledJob::Move(int t, TaskState to) {
    if (absl::Status s = states.Transition(t, to); !s.ok()) {
        NamedLogger("scheduler")->critical("job={} {}", record.id, std::string(s.message()));
        std::abort();
    }
}

void ScheduledJob::MoveTo(absl::Time now, JobState to) {
    if (absl::Status s = TransitionJob(record, to, now); !s.ok()) {
        NamedLogger("scheduler")->critical("{}", std::string(s.message()));
        std::abort();
    }
}

void ScheduledJob::Queue(const std::vector<int>& ready) {
    states.Resize(execution->task_count());
    tasks.resize(execution->task_count());
    for (int t : ready) {
        if (states.state(t) == TaskState::kWaiting) Move(t, TaskState::kQueued);
    }
}

void ScheduledJob::Sync() {
    record.tasks_done = int(execution->tasks_done());
    record.tasks_total = execution->tasks_total();
    record.stats = execution->stats();
    // A shot's progress from its execution; the paths of the frames written are the record's.
    // Both in frame order; a record from before the job's first Sync has none.
    std::vector<FrameProgress> frames = execution->Frames();
    if (record.frames.size() == frames.size()) {
        for (size_t i = 0; i < frames.size(); ++i) {
            frames[i].result_path = std::move(record.frames[i].result_path);
            frames[i].times = record.frames[i].times;
        }
    }
    record.frames = std::move(frames);
    record.tasks_running = IsFinal(record.state) ? 0 : states.running();
}

std::string ScheduledJob::WorkerOf(int t, const LeaseTable& leases) const {
    std::string worker = leases.LastHolder(record.id, t);
    return worker.empty() ? tasks[size_t(t)].recorded_worker : worker;
}

TaskHistory ScheduledJob::History(int t, const LeaseTable& leases) const {
    const Task& task = tasks[size_t(t)];
    return {.attempts = task.attempts,
            .failures = task.failures,
            .worker = WorkerOf(t, leases),
            .leased = task.leased_at,
            .finished = task.finished,
            .times = task.times,
            .samples = execution->TaskSamples(t),
            .frame = task.frame};
}

void ScheduledJob::Restore(int t, const TaskHistory& history) {
    Task& task = tasks[size_t(t)];
    task.attempts = history.attempts;
    task.failures = history.failures;
    task.recorded_worker = history.worker;
    task.leased_at = history.leased;
    task.finished = history.finished;
    task.times = history.times;
    task.frame = history.frame;
}

void ScheduledJob::AddTimes(int t, const TaskResult& result) {
    Task& task = tasks[size_t(t)];
    task.times = result.times;
    if (result.parts.empty()) task.frame = result.frame;
    record.times += result.times;
    Sync();  // the record lists the frames
    const auto add_to_frame = [&](const TaskResult& part) {
        for (FrameProgress& frame : record.frames) {
            if (part.frame && frame.frame == *part.frame) frame.times += part.times;
        }
    };
    if (result.parts.empty()) add_to_frame(result);
    for (const TaskResult& part : result.parts) add_to_frame(part);
}

std::vector<TaskStatus> ScheduledJob::Statuses(const LeaseTable& leases, absl::Time now) const {
    std::vector<TaskStatus> statuses(tasks.size());
    for (int t = 0; t < int(tasks.size()); ++t) {
        const Task& task = tasks[size_t(t)];
        TaskStatus& status = statuses[size_t(t)];
        status.index = t;
        switch (states.state(t)) {
            case TaskState::kWaiting:
                status.state = TaskStatus::State::kWaiting;
                break;
            case TaskState::kQueued:
                status.state = TaskStatus::State::kQueued;
                break;
            case TaskState::kLeased:
                status.state = TaskStatus::State::kRunning;
                break;
            case TaskState::kDone:
                status.state = TaskStatus::State::kDone;
                break;
            case TaskState::kDropped:
                status.state = TaskStatus::State::kDropped;
                break;
        }
        execution->Describe(t, status);
        status.attempts = task.attempts;
        status.failures = task.failures;
        status.last_error = task.last_error;
        if (task.attempts == 0) continue;  // never leased: no holder, no times
        status.worker = WorkerOf(t, leases);
        status.leased = task.leased_at;
        status.finished = task.finished;
        status.times = task.times;
        if (status.state == TaskStatus::State::kDone) {
            status.duration = task.finished - task.leased_at;
        } else if (status.state == TaskStatus::State::kRunning) {
            status.duration = now - task.leased_at;
        }
    }
    // An ended job's tasks that were not done never will be: its failing task included, whose
    // last failure ended the job before it went back to the queue.
    if (IsFinal(record.state)) {
        for (TaskStatus& status : statuses) {
            if (status.state != TaskStatus::State::kDone)
                status.state = TaskStatus::State::kDropped;
        }
    }
    return statuses;
}

}  // namespace lf
