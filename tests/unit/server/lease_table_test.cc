// The lease table alone, with made-up times: leases come out once their deadline has passed,
// earliest first, a moved or ended lease never comes out early, ids are unguessable and only
// ever looked up, and a job's leases are forgotten with it.
#include "lf/server/lease_table.h"

#include <gtest/gtest.h>

#include <set>

namespace lf {
namespace {

const absl::Time kT0 = absl::FromUnixSeconds(1000);

TEST(LeaseTable, ExpiredComeOutEarliestFirst) {
    LeaseTable t;
    const std::string b = t.Grant("j", 1, 1, "w", kT0 + absl::Seconds(2));
    const std::string a = t.Grant("j", 0, 1, "w", kT0 + absl::Seconds(1));
    t.Grant("j", 2, 1, "w", kT0 + absl::Seconds(3));
    EXPECT_TRUE(t.TakeExpired(kT0).empty());
    EXPECT_EQ(t.TakeExpired(kT0 + absl::Seconds(2)), (std::vector<std::string>{a, b}));
    EXPECT_EQ(t.current_count(), 1u);
    EXPECT_TRUE(t.TakeExpired(kT0 + absl::Seconds(2)).empty());
    // Expired leases stay known, no longer current, for their late results.
    ASSERT_NE(t.Find(a), nullptr);
    EXPECT_FALSE(t.Find(a)->current);
    EXPECT_EQ(t.Find(a)->task, 0);
    EXPECT_FALSE(t.Extend(a, kT0 + absl::Hours(1)));
}

TEST(LeaseTable, ExtendedLeaseWaitsForItsNewDeadline) {
    LeaseTable t;
    const std::string a = t.Grant("j", 0, 1, "w", kT0 + absl::Seconds(1));
    EXPECT_TRUE(t.Extend(a, kT0 + absl::Seconds(5)));  // a heartbeat
    EXPECT_EQ(t.current_count(), 1u);
    EXPECT_TRUE(t.TakeExpired(kT0 + absl::Seconds(4)).empty());
    EXPECT_EQ(t.TakeExpired(kT0 + absl::Seconds(5)), std::vector<std::string>{a});
}

TEST(LeaseTable, EndedLeaseNeverExpires) {
    LeaseTable t;
    const std::string a = t.Grant("j", 0, 1, "w", kT0);
    const std::string b = t.Grant("j", 1, 1, "w", kT0);
    const std::string c = t.Grant("j", 1, 2, "v", kT0);
    t.End(a);
    t.End("never there");
    t.EndTask("j", 1);
    EXPECT_TRUE(t.TakeExpired(kT0 + absl::Hours(1)).empty());
    EXPECT_EQ(t.current_count(), 0u);
    EXPECT_TRUE(t.Current("j", 1).empty());
    EXPECT_EQ(t.LastHolder("j", 1), "v");
    EXPECT_NE(t.Find(b), nullptr);
    EXPECT_NE(t.Find(c), nullptr);
}

TEST(LeaseTable, IdsAreRandomAndDistinctAcrossTables) {
    LeaseTable one, two;
    std::set<std::string> ids;
    for (int i = 0; i < 1000; ++i) {
        const std::string a = one.Grant("j", i, 1, "w", kT0);
        const std::string b = two.Grant("j", i, 1, "w", kT0);
        EXPECT_EQ(a.size(), 32u);
        EXPECT_EQ(a.find_first_not_of("0123456789abcdef"), std::string::npos);
        ids.insert(a);
        ids.insert(b);
        // Neither table knows the other's leases.
        EXPECT_EQ(one.Find(b), nullptr);
        EXPECT_EQ(two.Find(a), nullptr);
    }
    EXPECT_EQ(ids.size(), 2000u);
}

TEST(LeaseTable, MadeUpIdsAreUnknown) {
    LeaseTable t;
    const std::string real = t.Grant("job-1", 3, 1, "w", kT0);
    for (const std::string& forged : {std::string("job-1/3/x-1"), std::string("job-1/3/1"),
                                      std::string(""), real.substr(1), real + "0"}) {
        EXPECT_EQ(t.Find(forged), nullptr) << forged;
        EXPECT_FALSE(t.Extend(forged, kT0 + absl::Hours(1))) << forged;
    }
    const Lease* lease = t.Find(real);
    ASSERT_NE(lease, nullptr);
    EXPECT_EQ(lease->job_id, "job-1");
    EXPECT_EQ(lease->worker, "w");
}

TEST(LeaseTable, AnEndedJobsLeasesAreForgotten) {
    LeaseTable t;
    const std::string a = t.Grant("a", 0, 1, "w", kT0);
    const std::string b = t.Grant("b", 0, 1, "v", kT0);
    t.ForgetJob("a");
    EXPECT_EQ(t.Find(a), nullptr);
    EXPECT_NE(t.Find(b), nullptr);
    EXPECT_EQ(t.current_count(), 1u);
    EXPECT_EQ(t.LastHolder("a", 0), "");
    const std::map<std::string, const Lease*> held = t.CurrentByWorker();
    ASSERT_EQ(held.size(), 1u);
    EXPECT_EQ(held.at("v")->job_id, "b");
}

TEST(LeaseTable, TaskLeasesByAttempt) {
    LeaseTable t;
    t.Grant("j", 0, 1, "w", kT0 + absl::Seconds(1));
    t.Grant("j", 0, 2, "v", kT0 + absl::Seconds(2));  // a second, speculative lease
    const std::vector<const Lease*> current = t.Current("j", 0);
    ASSERT_EQ(current.size(), 2u);
    EXPECT_EQ(current[0]->attempt, 1);
    EXPECT_EQ(current[1]->worker, "v");
    EXPECT_EQ(t.TakeExpired(kT0 + absl::Seconds(1)).size(), 1u);
    ASSERT_EQ(t.Current("j", 0).size(), 1u);
    EXPECT_EQ(t.Current("j", 0)[0]->attempt, 2);
}

}  // namespace
}  // namespace lf
