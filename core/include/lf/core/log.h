// Named spdlog loggers for every module ("scene", "render", "radiosity", "scheduler", ...): they
// share the default logger's sinks and level, and every line names its module.
#pragma once

#include <spdlog/spdlog.h>

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace lf {

// Thread-safe; the same logger for the same name.
std::shared_ptr<spdlog::logger> NamedLogger(const std::string& name);

// A value from outside (the wire, a file) fit for one log line: control characters, backslashes
// and bytes outside ASCII become escapes (\n, \x1b), so a value cannot forge a line or move the
// terminal; beyond `max_bytes` it is cut, saying how long it was.
std::string LogSafe(std::string_view value, size_t max_bytes = 256);

}  // namespace lf
