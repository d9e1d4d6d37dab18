#include "lf/core/cancel.h"

#include <utility>

namespace lf {
namespace {

std::function<void()>& PollObserver() {
    static std::function<void()> observer;
    return observer;
}
std::atomic<bool> observed{false};

}  // namespace

bool CancelRequested(const std::atomic<bool>* cancel) {
    if (cancel == nullptr) return false;
    if (observed.load(std::memory_order_acquire)) PollObserver()();
    return cancel->load(std::memory_order_relaxed);
}

void SetCancelPollObserverForTesting(std::function<void()> observer) {
    observed = false;
    PollObserver() = std::move(observer);
    observed = bool(PollObserver());
}

}  // namespace lf
