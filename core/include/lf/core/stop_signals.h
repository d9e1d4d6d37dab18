// SIGINT and SIGTERM as a request to stop, for the server and worker mains: blocked in every
// thread (construct this before starting any), then received by whoever calls Wait().
#pragma once

#include <signal.h>

namespace lf {

class StopSignals {
  public:
    StopSignals() {
        sigemptyset(&signals_);
        sigaddset(&signals_, SIGINT);
        sigaddset(&signals_, SIGTERM);
        pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
    }

    // Blocks until one arrives; returns its number.
    int Wait() const {
        int signal = 0;
        sigwait(&signals_, &signal);
        return signal;
    }

  private:
    sigset_t signals_;
};

}  // namespace lf
