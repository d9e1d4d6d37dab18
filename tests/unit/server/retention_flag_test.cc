// --retention takes days, which absl::ParseDuration does not, and refuses what is not a
// duration rather than guessing a unit.
#include "lf/server/retention_flag.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

TEST(RetentionFlagTest, DaysHoursMinutesAndZero) {
    EXPECT_EQ(*ParseRetention("7d"), absl::Hours(24 * 7));
    EXPECT_EQ(*ParseRetention("1d12h"), absl::Hours(36));
    EXPECT_EQ(*ParseRetention("1.5d"), absl::Hours(36));
    EXPECT_EQ(*ParseRetention("12h"), absl::Hours(12));
    EXPECT_EQ(*ParseRetention("30m"), absl::Minutes(30));
    EXPECT_EQ(*ParseRetention("0"), absl::ZeroDuration());
}

TEST(RetentionFlagTest, WhatIsNotADurationIsRefusedNamingTheForm) {
    for (const char* text : {"", "12", "d", "7days", "-1h", "-2d", "1d-12h", "7w", "inf", "h"}) {
        const absl::StatusOr<absl::Duration> d = ParseRetention(text);
        EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument) << text;
        EXPECT_NE(d.status().message().find("such as 7d"), std::string_view::npos) << text;
    }
}

}  // namespace
}  // namespace lf
