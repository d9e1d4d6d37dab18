#include "lf/job/farm_stats.h"

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"

namespace lf {
namespace {

const absl::Time kNow = absl::FromUnixSeconds(1795000000);  // 2026-11-18T11:06:40Z

TEST(ParseSince, DurationsCountBackFromNow) {
    EXPECT_EQ(*ParseSince("7d", kNow), kNow - absl::Hours(7 * 24));
    EXPECT_EQ(*ParseSince("24h", kNow), kNow - absl::Hours(24));
    EXPECT_EQ(*ParseSince("30m", kNow), kNow - absl::Minutes(30));
    EXPECT_EQ(*ParseSince("45s", kNow), kNow - absl::Seconds(45));
}

TEST(ParseSince, DatesAndTimesAreUtc) {
    EXPECT_EQ(*ParseSince("2026-11-01", kNow), absl::FromUnixSeconds(1793491200));
    EXPECT_EQ(*ParseSince("2026-11-01T08:00:00Z", kNow), absl::FromUnixSeconds(1793520000));
    EXPECT_EQ(*ParseSince("2026-11-01T09:00:00+01:00", kNow), absl::FromUnixSeconds(1793520000));
}

TEST(ParseSince, RefusesWhatItCannotReadNamingTheText) {
    for (const char* bad : {"", "7", "d", "7w", "-7d", "0h", "1.5h", "7 d", "yesterday",
                            "2026-13-01", "2026-11-01T25:00:00Z"}) {
        const absl::StatusOr<absl::Time> since = ParseSince(bad, kNow);
        ASSERT_FALSE(since.ok()) << bad;
        EXPECT_EQ(since.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(since.status().message().find(absl::StrCat("--since ", bad, ":")),
                  std::string::npos)
            << since.status();
    }
}

TEST(ParseSince, RefusesAStartInTheFuture) {
    const absl::StatusOr<absl::Time> since = ParseSince("2027-01-01", kNow);
    ASSERT_FALSE(since.ok());
    EXPECT_NE(since.status().message().find("in the future"), std::string::npos);
    EXPECT_TRUE(ParseSince("2026-11-18T11:06:40Z", kNow).ok());  // now itself is fine
}

TEST(StatsAccumulator, AddsRowsUpPerOwnerAndPerWorkerSortedByName) {
    StatsAccumulator acc;
    acc.AddJobs("bob", JobState::kSucceeded, 2);
    acc.AddJobs("bob", JobState::kFailed, 1);
    acc.AddJobs("alice", JobState::kCancelled, 1);
    acc.AddJobs("alice", JobState::kRunning, 1);
    acc.AddJobs("alice", JobState::kQueued, 2);
    acc.AddTasks("bob", "w2", 3, 300, {.render_seconds = 3, .cpu_seconds = 6});
    acc.AddTasks("bob", "w1", 1, 100, {.render_seconds = 1, .cpu_seconds = 2});
    acc.AddTasks("alice", "w1", 2, 50, {.render_seconds = 0.5, .cpu_seconds = 1});
    acc.AddFailures("w3", 4);
    acc.AddFailures("w1", 1);
    const FarmStats stats = std::move(acc).Take(kNow);
    EXPECT_EQ(stats.since, kNow);
    ASSERT_EQ(stats.owners.size(), 2u);
    EXPECT_EQ(stats.owners[0], (OwnerStats{"alice", 0, 0, 1, 3, 2, 50, {0.5, 1}}));
    EXPECT_EQ(stats.owners[1], (OwnerStats{"bob", 2, 1, 0, 0, 4, 400, {4, 8}}));
    ASSERT_EQ(stats.workers.size(), 3u);
    EXPECT_EQ(stats.workers[0], (WorkerStats{"w1", 3, 1, {1.5, 3}}));
    EXPECT_EQ(stats.workers[1], (WorkerStats{"w2", 3, 0, {3, 6}}));
    EXPECT_EQ(stats.workers[2], (WorkerStats{"w3", 0, 4, {}}));
}

TEST(StatsAccumulator, NothingAddedIsNoLines) {
    const FarmStats stats = StatsAccumulator().Take(absl::InfinitePast());
    EXPECT_TRUE(stats.owners.empty());
    EXPECT_TRUE(stats.workers.empty());
}

}  // namespace
}  // namespace lf
