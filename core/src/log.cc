#include "lf/core/log.h"

#include <mutex>

namespace lf {

std::shared_ptr<spdlog::logger> NamedLogger(const std::string& name) {
    static std::mutex mutex;
    std::lock_guard<std::mutex> lock(mutex);
    if (std::shared_ptr<spdlog::logger> log = spdlog::get(name)) return log;
    std::shared_ptr<spdlog::logger> log = spdlog::default_logger()->clone(name);
    spdlog::register_logger(log);
    return log;
}

}  // namespace lf
