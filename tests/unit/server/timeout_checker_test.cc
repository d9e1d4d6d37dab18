// The timeout checker ticks again and again until stopped, and no tick starts after Stop.
#include "lf/server/timeout_checker.h"

#include <gtest/gtest.h>

#include <atomic>

#include "absl/time/clock.h"

namespace lf {
namespace {

TEST(TimeoutChecker, TicksUntilStoppedAndNotAfter) {
    std::mutex mutex;
    std::condition_variable ticked;
    int ticks = 0;
    TimeoutChecker checker(absl::Milliseconds(1), [&] {
        std::lock_guard<std::mutex> lock(mutex);
        ++ticks;
        ticked.notify_all();
    });
    {
        std::unique_lock<std::mutex> lock(mutex);
        ASSERT_TRUE(ticked.wait_for(lock, std::chrono::seconds(30), [&] { return ticks >= 3; }));
    }
    checker.Stop();  // returns once the thread has ended: no tick can follow
    const int at_stop = ticks;
    checker.Stop();  // twice is harmless
    EXPECT_EQ(ticks, at_stop);
}

TEST(TimeoutChecker, StopDoesNotWaitForTheInterval) {
    std::atomic<int> ticks{0};
    const absl::Time start = absl::Now();
    {
        TimeoutChecker checker(absl::Hours(1), [&] { ++ticks; });
    }  // destroyed: stopped
    EXPECT_EQ(ticks, 0);
    EXPECT_LT(absl::Now() - start, absl::Minutes(10));  // not the hour
}

}  // namespace
}  // namespace lf
