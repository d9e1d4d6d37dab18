#include "lf/job/task_status.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace lf {
namespace {

TEST(TaskStatusNames, EveryStateHasItsOwnNameAndReadsBack) {
    std::set<std::string> names;
    for (TaskStatus::State s :
         {TaskStatus::State::kWaiting, TaskStatus::State::kQueued, TaskStatus::State::kRunning,
          TaskStatus::State::kDone, TaskStatus::State::kDropped}) {
        names.insert(TaskStatusName(s));
        EXPECT_EQ(TaskStatusFromName(TaskStatusName(s)), s) << TaskStatusName(s);
    }
    EXPECT_EQ(names.size(), 5u);
    EXPECT_EQ(TaskStatusFromName("Done"), std::nullopt);
    EXPECT_EQ(TaskStatusFromName(""), std::nullopt);
}

}  // namespace
}  // namespace lf
