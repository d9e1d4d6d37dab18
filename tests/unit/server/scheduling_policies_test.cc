// The scheduler's policies alone: when a running task is a straggler worth a second lease, and
// when an adaptive job's time limit is reached; and where sweep tasks are numbered.
#include <gtest/gtest.h>

#include "lf/server/speculation.h"
#include "lf/job/sweep_task_numbering.h"
#include "lf/job/time_limit.h"

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

TEST(SweepTaskNumbering, SweepChunksFollowTheTilesInOrder) {
    const SweepTaskNumbering n{.tiles = 10, .chunks = 3};
    EXPECT_FALSE(n.FromIndex(9).has_value());
    EXPECT_EQ(n.ToIndex({0, 0}), 10);
    EXPECT_EQ(n.ToIndex({2, 1}), 17);
    for (int index = 10; index < 40; ++index) {
        const std::optional<SweepTaskNumbering::SweepChunk> at = n.FromIndex(index);
        ASSERT_TRUE(at.has_value());
        EXPECT_LT(at->chunk, 3);
        EXPECT_EQ(n.ToIndex(*at), index);
    }
    EXPECT_EQ(*n.FromIndex(17), (SweepTaskNumbering::SweepChunk{2, 1}));
}

}  // namespace
}  // namespace lf
