// Named spdlog loggers for every module ("scene", "render", "radiosity", "scheduler", ...): they
// share the default logger's sinks and level, and every line names its module.
#pragma once

#include <spdlog/spdlog.h>

#include <memory>
#include <string>

namespace lf {

// Thread-safe; the same logger for the same name.
std::shared_ptr<spdlog::logger> NamedLogger(const std::string& name);

}  // namespace lf
