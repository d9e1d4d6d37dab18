#include "lf/server/timeout_checker.h"

namespace lf {

TimeoutChecker::TimeoutChecker(absl::Duration interval, std::function<void()> tick)
    : interval_(interval), tick_(std::move(tick)), thread_([this] { Run(); }) {}

TimeoutChecker::~TimeoutChecker() { Stop(); }

void TimeoutChecker::Stop() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    stop_cv_.notify_all();
    if (thread_.joinable()) thread_.join();
}

void TimeoutChecker::Run() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (
        !stop_cv_.wait_for(lock, absl::ToChronoNanoseconds(interval_), [this] { return stop_; })) {
        // Unlocked, so that Stop need not wait for a tick to be asked to end.
        lock.unlock();
        tick_();
        lock.lock();
    }
}

}  // namespace lf
