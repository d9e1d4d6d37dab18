// A task and its log as the coordinator shows them: what `lightfarm tasks`, `lightfarm logs`
// and the dashboard list (wire: ListTasks, GetTaskLogs).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/time/time.h"

namespace lf {

enum class TaskKind { kTile, kSplat, kRadiositySweep };

// What a task cost on its worker (issue 30's history): the wall seconds of its render and the
// worker process' CPU seconds over them (CLOCK_PROCESS_CPUTIME_ID: a worker runs one task at a
// time, so they are the task's).
struct TaskTimes {
    double render_seconds = 0, cpu_seconds = 0;
    TaskTimes& operator+=(const TaskTimes& o) {
        render_seconds += o.render_seconds;
        cpu_seconds += o.cpu_seconds;
        return *this;
    }
    friend bool operator==(const TaskTimes&, const TaskTimes&) = default;
};

// A worker's figures as the farm keeps them: what is not finite or below 0 (a NaN from a broken
// or hostile worker would poison every sum, and fail the history's write) reads as 0, and each
// is at most kMaxTaskSeconds (30 days; no task runs that long).
inline constexpr double kMaxTaskSeconds = 30 * 86400.0;
TaskTimes ReportedTimes(double render_seconds, double cpu_seconds);

struct TaskStatus {
    enum class State { kWaiting, kQueued, kRunning, kDone, kDropped };
    int index = 0;
    State state = State::kQueued;
    TaskKind kind = TaskKind::kTile;
    int x = 0, y = 0, width = 0, height = 0;  // a tile's pixels; the whole frame for kSplat
    uint64_t samples = 0;                     // per pixel, for a tile
    std::vector<int> frames;                  // a shot's task: the frames it renders
    int attempts = 0, failures = 0;
    std::string worker;                          // of the current or last lease
    absl::Time leased = absl::InfinitePast();    // the current or last lease
    absl::Time finished = absl::InfinitePast();  // its result merged
    absl::Duration duration;                     // lease to merged result, or running so far
    std::string last_error;
    int log_lines = 0;
    TaskTimes times;  // a done task's, as its worker measured them
};

// "waiting", "queued", "running", "done", "dropped": as the dashboard shows a state and the
// task log store records it.
const char* TaskStatusName(TaskStatus::State state);
// The state a TaskStatusName names; nullopt for any other string.
std::optional<TaskStatus::State> TaskStatusFromName(std::string_view name);
// "tile", "frame" (kSplat: the name the dashboard, the task log store and the wire's FRAME
// already use), "sweep".
const char* TaskKindName(TaskKind kind);

// One line a worker logged while running a task.
struct TaskLogLine {
    int64_t seq = 0;  // increases through the job's log
    int task = 0;
    int attempt = 1;
    std::string worker;
    absl::Time time;    // the worker's clock
    std::string level;  // spdlog's level name
    std::string text;
};

struct TaskLogPage {
    std::vector<TaskLogLine> lines;
    int64_t next_seq = 0;  // after_seq of the next page
    bool job_ended = false;
};

}  // namespace lf
