// The task state machine: every move the diagram allows, none it does not, and the queue and
// the running count that follow from the states.
#include "lf/server/task_state_machine.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

constexpr TaskState kAll[] = {TaskState::kWaiting, TaskState::kQueued, TaskState::kLeased,
                              TaskState::kDone, TaskState::kDropped};

TEST(TaskStateMachine, OnlyTheDiagramsMovesAreLegal) {
    const std::set<std::pair<TaskState, TaskState>> legal = {
        {TaskState::kWaiting, TaskState::kQueued},  {TaskState::kWaiting, TaskState::kDone},
        {TaskState::kWaiting, TaskState::kDropped}, {TaskState::kQueued, TaskState::kLeased},
        {TaskState::kQueued, TaskState::kDone},     {TaskState::kQueued, TaskState::kDropped},
        {TaskState::kLeased, TaskState::kQueued},   {TaskState::kLeased, TaskState::kDone},
        {TaskState::kLeased, TaskState::kDropped},
    };
    for (TaskState from : kAll) {
        for (TaskState to : kAll) {
            EXPECT_EQ(IsLegalTaskTransition(from, to), legal.count({from, to}) > 0)
                << TaskStateName(from) << " -> " << TaskStateName(to);
        }
    }
}

TEST(TaskStateMachine, IllegalMoveIsRefusedAndChangesNothing) {
    TaskStateMachine m;
    const int t = m.Add();
    ASSERT_TRUE(m.Transition(t, TaskState::kQueued).ok());
    ASSERT_TRUE(m.Transition(t, TaskState::kLeased).ok());
    ASSERT_TRUE(m.Transition(t, TaskState::kDone).ok());
    const absl::Status again = m.Transition(t, TaskState::kQueued);
    EXPECT_EQ(again.code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(again.message().find("from done to queued"), std::string::npos) << again;
    EXPECT_EQ(m.state(t), TaskState::kDone);
    EXPECT_TRUE(m.queued().empty());
    EXPECT_EQ(m.count(TaskState::kDone), 1);
    EXPECT_EQ(m.Transition(5, TaskState::kQueued).code(), absl::StatusCode::kFailedPrecondition);
}

TEST(TaskStateMachine, QueueAndRunningCountFollowTheStates) {
    TaskStateMachine m;
    m.Resize(4);
    EXPECT_EQ(m.count(TaskState::kWaiting), 4);
    for (int t = 0; t < 4; ++t) ASSERT_TRUE(m.Transition(t, TaskState::kQueued).ok());
    EXPECT_EQ(m.queued(), (std::set<int>{0, 1, 2, 3}));
    ASSERT_TRUE(m.Transition(2, TaskState::kLeased).ok());
    ASSERT_TRUE(m.Transition(0, TaskState::kLeased).ok());
    EXPECT_EQ(m.queued(), (std::set<int>{1, 3}));
    EXPECT_EQ(m.running(), 2);
    ASSERT_TRUE(m.Transition(2, TaskState::kQueued).ok());  // its lease failed
    ASSERT_TRUE(m.Transition(0, TaskState::kDropped).ok());
    ASSERT_TRUE(m.Transition(3, TaskState::kDone).ok());  // a late result
    EXPECT_EQ(m.queued(), (std::set<int>{1, 2}));
    EXPECT_EQ(m.running(), 0);
    EXPECT_EQ(m.count(TaskState::kDropped), 1);
    EXPECT_EQ(m.count(TaskState::kDone), 1);
    EXPECT_EQ(m.size(), 4u);
}

}  // namespace
}  // namespace lf
