// The timeout checker: a thread that calls `tick` every `interval` (expiring leases, enforcing
// time limits, forgetting silent workers) until it is stopped. Stop, or destruction, returns once
// a tick under way has ended; no tick starts after it.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include "absl/time/time.h"

namespace lf {

class TimeoutChecker {
  public:
    TimeoutChecker(absl::Duration interval, std::function<void()> tick);
    ~TimeoutChecker();
    TimeoutChecker(const TimeoutChecker&) = delete;
    TimeoutChecker& operator=(const TimeoutChecker&) = delete;

    void Stop();

  private:
    void Run();

    const absl::Duration interval_;
    const std::function<void()> tick_;
    std::mutex mutex_;
    std::condition_variable stop_cv_;
    bool stop_ = false;
    std::thread thread_;  // last: started once the rest is ready
};

}  // namespace lf
