#include "lf/client/progress_bar.h"

#include <unistd.h>

#include <cstdio>

namespace lf {

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)),
      enabled_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()) {}

void ProgressBar::Update(size_t done, size_t total) {
    if (!enabled_ || total == 0) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const int permille = int(1000 * done / total);
    if (permille == last_permille_) return;
    last_permille_ = permille;
    constexpr int kWidth = 40;
    const int filled = kWidth * permille / 1000;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double eta = done > 0 ? elapsed * double(total - done) / double(done) : 0.0;
    std::string bar(size_t(filled), '=');
    bar.resize(kWidth, ' ');
    std::fprintf(stderr, "\r%s [%s] %5.1f%% %zu/%zu  %.1fs elapsed, ~%.1fs left ", label_.c_str(),
                 bar.c_str(), permille / 10.0, done, total, elapsed, eta);
    std::fflush(stderr);
}

void ProgressBar::Finish() {
    if (!enabled_) return;
    std::fprintf(stderr, "\n");
}

}  // namespace lf
