// The timeout checker's bookkeeping: leases come out once their deadline has passed, earliest
// first, and a moved or removed lease never comes out early.
#include "server/lease_timeouts.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

const absl::Time kT0 = absl::FromUnixSeconds(1000);

TEST(LeaseTimeouts, ExpiredComeOutEarliestFirst) {
    LeaseTimeouts t;
    t.Set("b", kT0 + absl::Seconds(2));
    t.Set("a", kT0 + absl::Seconds(1));
    t.Set("c", kT0 + absl::Seconds(3));
    EXPECT_TRUE(t.TakeExpired(kT0).empty());
    EXPECT_EQ(t.TakeExpired(kT0 + absl::Seconds(2)), (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(t.size(), 1u);
    EXPECT_TRUE(t.TakeExpired(kT0 + absl::Seconds(2)).empty());
}

TEST(LeaseTimeouts, ExtendedLeaseWaitsForItsNewDeadline) {
    LeaseTimeouts t;
    t.Set("a", kT0 + absl::Seconds(1));
    t.Set("a", kT0 + absl::Seconds(5));  // a heartbeat
    EXPECT_EQ(t.size(), 1u);
    EXPECT_TRUE(t.TakeExpired(kT0 + absl::Seconds(4)).empty());
    EXPECT_EQ(t.TakeExpired(kT0 + absl::Seconds(5)), std::vector<std::string>{"a"});
}

TEST(LeaseTimeouts, RemovedLeaseNeverExpires) {
    LeaseTimeouts t;
    t.Set("a", kT0);
    t.Remove("a");
    t.Remove("never there");
    EXPECT_TRUE(t.TakeExpired(kT0 + absl::Hours(1)).empty());
    EXPECT_EQ(t.size(), 0u);
}

}  // namespace
}  // namespace lf
