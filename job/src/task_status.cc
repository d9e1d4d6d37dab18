#include "lf/job/task_status.h"

#include <algorithm>
#include <cmath>

namespace lf {

TaskTimes ReportedTimes(double render_seconds, double cpu_seconds) {
    const auto sane = [](double s) {
        return std::isfinite(s) ? std::clamp(s, 0.0, kMaxTaskSeconds) : 0.0;
    };
    return {sane(render_seconds), sane(cpu_seconds)};
}

const char* TaskStatusName(TaskStatus::State state) {
    switch (state) {
        case TaskStatus::State::kWaiting:
            return "waiting";
        case TaskStatus::State::kQueued:
            return "queued";
        case TaskStatus::State::kRunning:
            return "running";
        case TaskStatus::State::kDone:
            return "done";
        case TaskStatus::State::kDropped:
            return "dropped";
    }
    return "?";
}

std::optional<TaskStatus::State> TaskStatusFromName(std::string_view name) {
    for (TaskStatus::State s :
         {TaskStatus::State::kWaiting, TaskStatus::State::kQueued, TaskStatus::State::kRunning,
          TaskStatus::State::kDone, TaskStatus::State::kDropped}) {
        if (name == TaskStatusName(s)) return s;
    }
    return std::nullopt;
}

const char* TaskKindName(TaskKind kind) {
    switch (kind) {
        case TaskKind::kTile:
            return "tile";
        case TaskKind::kSplat:
            return "frame";
        case TaskKind::kRadiositySweep:
            return "sweep";
    }
    return "?";
}

}  // namespace lf
