// The "radiosity" logger shared by the radiosity sources: the application's if it registered
// one, else a clone of the default logger.
#pragma once

#include <spdlog/spdlog.h>

#include <memory>

namespace lf {

inline const std::shared_ptr<spdlog::logger>& RadiosityLog() {
    static const std::shared_ptr<spdlog::logger> log = [] {
        auto registered = spdlog::get("radiosity");
        return registered ? registered : spdlog::default_logger()->clone("radiosity");
    }();
    return log;
}

}  // namespace lf
