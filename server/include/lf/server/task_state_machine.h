// The states of one job's tasks, and the one function that changes them. The queue of a job and
// its count of running tasks follow from the states here, so they cannot disagree with them.
//
//   waiting -> queued -> leased -> done
//      |         |  ^------'  |
//      +---------+------------+--> dropped
//
// A task waits while it cannot start yet (a radiosity job's tiles wait for the solve); a leased
// task goes back to the queue when its lease fails or expires; done and dropped (an adaptive pass
// the time limit cut) are final. A task whose result is recorded may go straight to done from
// waiting or queued (a restart merging recorded results, a late result of an expired lease).
#pragma once

#include <array>
#include <set>
#include <vector>

#include "absl/status/status.h"

namespace lf {

enum class TaskState { kWaiting, kQueued, kLeased, kDone, kDropped };
const char* TaskStateName(TaskState state);
bool IsLegalTaskTransition(TaskState from, TaskState to);

class TaskStateMachine {
  public:
    // Appends a task in state `waiting` and returns its index.
    int Add();
    // Grows to `count` tasks, the new ones waiting.
    void Resize(size_t count);

    // The only way a task's state changes. FailedPrecondition, and nothing changed, for a move
    // the diagram above does not allow (or an index out of range).
    absl::Status Transition(int task, TaskState to);

    TaskState state(int task) const { return states_[size_t(task)]; }
    size_t size() const { return states_.size(); }
    // Queued tasks in index order.
    const std::set<int>& queued() const { return queued_; }
    int count(TaskState state) const { return counts_[size_t(state)]; }
    int running() const { return count(TaskState::kLeased); }

  private:
    std::vector<TaskState> states_;
    std::set<int> queued_;
    std::array<int, 5> counts_{};
};

}  // namespace lf
