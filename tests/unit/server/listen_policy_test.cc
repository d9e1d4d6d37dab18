#include "lf/server/listen_policy.h"

#include <gtest/gtest.h>

#include "absl/strings/match.h"

namespace lf {
namespace {

TEST(ListenPolicy, LoopbackAddresses) {
    for (const char* host : {"127.0.0.1", "127.1.2.3", "localhost", "LOCALHOST", "::1"}) {
        EXPECT_TRUE(IsLoopbackHost(host)) << host;
    }
    for (const char* host : {"0.0.0.0", "::", "10.0.0.1", "127.0.0", "127.0.0.1.5", "128.0.0.1",
                             "127.0.0.256", "localhost.evil.com", "", "1127.0.0.1"}) {
        EXPECT_FALSE(IsLoopbackHost(host)) << host;
    }
    EXPECT_EQ(ListenHost("[::1]:7070"), "::1");
    EXPECT_EQ(ListenHost("10.1.2.3:0"), "10.1.2.3");
}

TEST(ListenPolicy, BeyondLoopbackOnlyWithTlsOrInsecure) {
    EXPECT_TRUE(CheckListenPolicy("127.0.0.1:7070", false, false).ok());
    EXPECT_TRUE(CheckListenPolicy("[::1]:7070", false, false).ok());
    const absl::Status s = CheckListenPolicy("0.0.0.0:7070", false, false);
    EXPECT_TRUE(absl::IsFailedPrecondition(s));
    EXPECT_TRUE(absl::StrContains(s.message(), "0.0.0.0:7070 without TLS")) << s;
    EXPECT_TRUE(absl::StrContains(s.message(), "--insecure")) << s;
    EXPECT_TRUE(CheckListenPolicy("0.0.0.0:7070", true, false).ok());
    EXPECT_TRUE(CheckListenPolicy("10.0.0.5:7070", false, true).ok());
}

}  // namespace
}  // namespace lf
