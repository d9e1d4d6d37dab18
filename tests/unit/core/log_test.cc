// LogSafe: a value from the wire cannot forge a log line or reach the terminal raw, and a huge
// one is cut to a bound that says how long it was.
#include "lf/core/log.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

TEST(LogSafeTest, ControlCharactersAndBackslashesAreEscaped) {
    EXPECT_EQ(LogSafe("w1\n[info] job=x succeeded"), "w1\\n[info] job=x succeeded");
    EXPECT_EQ(LogSafe("a\rb\tc"), "a\\rb\\tc");
    EXPECT_EQ(LogSafe(std::string("\x1b[2J\0z", 6)), "\\x1b[2J\\x00z");
    EXPECT_EQ(LogSafe("back\\n"), "back\\\\n") << "an escape in the value stays distinguishable";
    EXPECT_EQ(LogSafe("caf\xc3\xa9"), "caf\\xc3\\xa9");
    EXPECT_EQ(LogSafe("worker-7 (host:1)"), "worker-7 (host:1)");
}

TEST(LogSafeTest, LongValueIsCutAndSaysItsLength) {
    const std::string huge(2 << 20, 'x');
    const std::string safe = LogSafe(huge, 16);
    EXPECT_EQ(safe, std::string(16, 'x') + "...(2097152 bytes)");
    EXPECT_EQ(LogSafe("short", 16), "short");
    // The bound is on the escaped text, so escapes do not stretch it.
    std::string eight_newlines;
    for (int i = 0; i < 8; ++i) eight_newlines += "\\n";
    EXPECT_EQ(LogSafe(std::string(100, '\n'), 16), eight_newlines + "...(100 bytes)");
    EXPECT_EQ(LogSafe("ab\x01", 5), "ab...(3 bytes)") << "an escape is never cut in half";
}

}  // namespace
}  // namespace lf
