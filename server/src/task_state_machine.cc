#include "lf/server/task_state_machine.h"

#include "absl/strings/str_cat.h"

namespace lf {

const char* TaskStateName(TaskState state) {
    switch (state) {
        case TaskState::kWaiting:
            return "waiting";
        case TaskState::kQueued:
            return "queued";
        case TaskState::kLeased:
            return "leased";
        case TaskState::kDone:
            return "done";
        case TaskState::kDropped:
            return "dropped";
    }
    return "unknown";
}

bool IsLegalTaskTransition(TaskState from, TaskState to) {
    switch (from) {
        case TaskState::kWaiting:
            return to == TaskState::kQueued || to == TaskState::kDone || to == TaskState::kDropped;
        case TaskState::kQueued:
            return to == TaskState::kLeased || to == TaskState::kDone || to == TaskState::kDropped;
        case TaskState::kLeased:
            return to == TaskState::kQueued || to == TaskState::kDone || to == TaskState::kDropped;
        case TaskState::kDone:
        case TaskState::kDropped:
            return false;
    }
    return false;
}

int TaskStateMachine::Add() {
    states_.push_back(TaskState::kWaiting);
    ++counts_[size_t(TaskState::kWaiting)];
    return int(states_.size()) - 1;
}

void TaskStateMachine::Resize(size_t count) {
    while (states_.size() < count) Add();
}

absl::Status TaskStateMachine::Transition(int task, TaskState to) {
    if (task < 0 || size_t(task) >= states_.size()) {
        return absl::FailedPreconditionError(
            absl::StrCat("task ", task, ": no such task (", states_.size(), " tasks)"));
    }
    TaskState& from = states_[size_t(task)];
    if (!IsLegalTaskTransition(from, to)) {
        return absl::FailedPreconditionError(absl::StrCat("task ", task, ": no transition from ",
                                                          TaskStateName(from), " to ",
                                                          TaskStateName(to)));
    }
    if (from == TaskState::kQueued) queued_.erase(task);
    if (to == TaskState::kQueued) queued_.insert(task);
    --counts_[size_t(from)];
    ++counts_[size_t(to)];
    from = to;
    return absl::OkStatus();
}

}  // namespace lf
