// A one-line progress bar on stderr, drawn only when stderr is a terminal.
#pragma once

#include <chrono>
#include <mutex>
#include <string>

namespace lf {

class ProgressBar {
  public:
    explicit ProgressBar(std::string label);
    void Update(size_t done, size_t total);  // thread-safe
    void Finish();

  private:
    std::string label_;
    bool enabled_;
    std::mutex mutex_;
    std::chrono::steady_clock::time_point start_;
    int last_permille_ = -1;
};

}  // namespace lf
