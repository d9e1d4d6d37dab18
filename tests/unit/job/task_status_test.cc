#include "lf/job/task_status.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// What a worker reports is kept only within reason: a NaN or negative time reads as 0, and none
// is above 30 days, so no worker can poison or swamp the sums.
TEST(ReportedTimes, NonFiniteAndNegativeReadAsZeroAndHugeAreCapped) {
    EXPECT_EQ(ReportedTimes(2.5, 4.75), (TaskTimes{2.5, 4.75}));
    EXPECT_EQ(ReportedTimes(std::nan(""), -1), (TaskTimes{0, 0}));
    EXPECT_EQ(ReportedTimes(-std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity()),
              (TaskTimes{0, 0}));
    EXPECT_EQ(ReportedTimes(1e308, kMaxTaskSeconds + 1),
              (TaskTimes{kMaxTaskSeconds, kMaxTaskSeconds}));
}

}  // namespace
}  // namespace lf
