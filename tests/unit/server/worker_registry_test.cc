// The worker registry keeps only the workers heard from within a lease, and forgetting the
// silent ones leaves the live ones.
#include "server/worker_registry.h"

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

}  // namespace
}  // namespace lf
