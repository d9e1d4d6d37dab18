// The worker registry keeps only the workers heard from within a lease, and forgetting the
// silent ones leaves the live ones.
#include "lf/server/worker_registry.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

const absl::Time kT0 = absl::FromUnixSeconds(1000);

TEST(WorkerRegistry, LiveWhileSeenWithinTheLease) {
    WorkerRegistry r(absl::Seconds(10));
    r.Seen("a", kT0);
    EXPECT_TRUE(r.IsLive("a", kT0 + absl::Seconds(9)));
    EXPECT_FALSE(r.IsLive("a", kT0 + absl::Seconds(10)));
    EXPECT_FALSE(r.IsLive("b", kT0));
    r.Seen("a", kT0 + absl::Seconds(9));  // seen again: live again for a lease
    EXPECT_TRUE(r.IsLive("a", kT0 + absl::Seconds(18)));
}

TEST(WorkerRegistry, ForgetsTheSilentAndKeepsTheLive) {
    WorkerRegistry r(absl::Seconds(10));
    for (int i = 0; i < 100'000; ++i) r.Seen("made-up-" + std::to_string(i), kT0);
    r.Seen("real", kT0);
    EXPECT_EQ(r.size(), 100'001u);
    r.Seen("real", kT0 + absl::Seconds(8));
    EXPECT_EQ(r.ForgetSilent(kT0 + absl::Seconds(9)), 0);
    EXPECT_EQ(r.ForgetSilent(kT0 + absl::Seconds(10)), 100'000);
    EXPECT_EQ(r.size(), 1u);
    EXPECT_TRUE(r.IsLive("real", kT0 + absl::Seconds(10)));
}

TEST(WorkerRegistry, KeepsWhatAWorkerSaidOfItselfUntilItSaysAgain) {
    WorkerRegistry r(absl::Seconds(10));
    const WorkerDescription first{"render-07", "ipv4:10.0.0.7:40000", "v1"};
    r.Seen("a", kT0, &first);
    r.Seen("a", kT0 + absl::Seconds(1));  // a heartbeat says nothing of itself
    r.Seen("b", kT0 + absl::Seconds(2));
    std::vector<WorkerRegistry::Entry> listed = r.List();
    ASSERT_EQ(listed.size(), 2u);
    EXPECT_EQ(listed[0].id, "a");
    EXPECT_EQ(listed[0].about.name, "render-07");
    EXPECT_EQ(listed[0].about.address, "ipv4:10.0.0.7:40000");
    EXPECT_EQ(listed[0].last_seen, kT0 + absl::Seconds(1));
    EXPECT_EQ(listed[1].id, "b");
    EXPECT_EQ(listed[1].about.name, "");

    const WorkerDescription moved{"render-07", "ipv4:10.0.0.8:40001", "v1"};
    r.Seen("a", kT0 + absl::Seconds(3), &moved);
    EXPECT_EQ(r.List()[0].about.address, "ipv4:10.0.0.8:40001");
    r.ForgetSilent(kT0 + absl::Seconds(12.5));  // b silent for 10.5 s, a for 9.5 s
    listed = r.List();
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_EQ(listed[0].id, "a");
}

}  // namespace
}  // namespace lf
