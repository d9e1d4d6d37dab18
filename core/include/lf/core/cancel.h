// A long computation (meshing, form factors, a radiosity solve) is cancelled from another
// thread through a flag it polls between units of work, returning Cancelled once it is set.
#pragma once

#include <atomic>
#include <functional>

namespace lf {

// Whether `cancel` (null: never) is set.
bool CancelRequested(const std::atomic<bool>* cancel);

// For tests that count units of work instead of seconds: `observer` runs at every poll of a
// non-null flag, on the polling thread, before the flag is read (so it may set it). Set and clear
// it only while nothing polls; nullptr clears it.
void SetCancelPollObserverForTesting(std::function<void()> observer);

}  // namespace lf
