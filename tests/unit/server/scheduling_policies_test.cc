// The scheduler's policies alone: when a running task is a straggler worth a second lease, and
// when an adaptive job's time limit is reached; and where sweep tasks are numbered.
#include <gtest/gtest.h>

#include "lf/job/sweep_task_numbering.h"
#include "lf/job/time_limit.h"
#include "lf/server/speculation.h"

namespace lf {
namespace {

TEST(SpeculationPolicy, StragglerAfterTheMinimumUntilTasksAreTimed) {
    const SpeculationPolicy p(absl::Seconds(1));
    EXPECT_EQ(p.Limit(), absl::Seconds(1));
    EXPECT_FALSE(p.IsStraggler(absl::Milliseconds(999)));
    EXPECT_TRUE(p.IsStraggler(absl::Seconds(1)));
}

TEST(SpeculationPolicy, StragglerAfterTwiceTheMeanTaskTime) {
    SpeculationPolicy p(absl::Seconds(1));
    p.TaskDone(absl::Seconds(2));
    p.TaskDone(absl::Seconds(4));
    EXPECT_EQ(p.Limit(), absl::Seconds(6));
    EXPECT_FALSE(p.IsStraggler(absl::Seconds(5)));
    EXPECT_TRUE(p.IsStraggler(absl::Seconds(6)));
    SpeculationPolicy fast(absl::Seconds(1));
    fast.TaskDone(absl::Milliseconds(100));
    EXPECT_EQ(fast.Limit(), absl::Seconds(1)) << "never below the minimum";
}

TEST(TimeLimit, ReachedOnlyOnceStartedAndPastTheLimit) {
    const absl::Time t0 = absl::FromUnixSeconds(1000);
    const AdaptiveSettings limited{.time_limit = 5};
    EXPECT_FALSE(TimeLimitReached(limited, absl::InfinitePast(), t0));
    EXPECT_FALSE(TimeLimitReached(limited, t0, t0 + absl::Milliseconds(4999)));
    EXPECT_TRUE(TimeLimitReached(limited, t0, t0 + absl::Seconds(5)));
    EXPECT_FALSE(TimeLimitReached(AdaptiveSettings{.target_error = 0.1}, t0, t0 + absl::Hours(9)));
}

// Sweeps' tasks follow the tiles and each other in order, each with the chunks it covers; an
// index of a tile or beyond the last sweep is no sweep task.
TEST(SweepTaskNumbering, SweepTasksFollowTheTilesInOrder) {
    SweepTaskNumbering n(10);
    EXPECT_FALSE(n.FromIndex(9).has_value());
    EXPECT_FALSE(n.FromIndex(10).has_value());
    EXPECT_EQ(n.Append({{0}, {1}, {2}}), (std::vector<int>{10, 11, 12}));
    EXPECT_EQ(n.Append({{0, 2}, {1}}), (std::vector<int>{13, 14}));
    EXPECT_EQ(n.Append({{0, 1, 2}}), std::vector<int>{15});
    EXPECT_EQ(n.end(), 16);
    EXPECT_EQ(n.sweeps(), 3);
    EXPECT_FALSE(n.FromIndex(9).has_value());
    EXPECT_FALSE(n.FromIndex(16).has_value());
    EXPECT_FALSE(n.FromIndex(-1).has_value());
    const std::vector<std::pair<int, std::vector<int>>> want = {
        {0, {0}}, {0, {1}}, {0, {2}}, {1, {0, 2}}, {1, {1}}, {2, {0, 1, 2}}};
    for (int index = 10; index < 16; ++index) {
        const std::optional<SweepTaskNumbering::SweepTask> at = n.FromIndex(index);
        ASSERT_TRUE(at.has_value()) << index;
        EXPECT_EQ(at->sweep, want[size_t(index - 10)].first) << index;
        EXPECT_EQ(std::vector<int>(at->chunks.begin(), at->chunks.end()),
                  want[size_t(index - 10)].second)
            << index;
    }
}

}  // namespace
}  // namespace lf
