#include "lf/core/log.h"

#include <cstdio>
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

std::string LogSafe(std::string_view value, size_t max_bytes) {
    std::string out;
    const std::string_view kept = value.substr(0, max_bytes);
    out.reserve(kept.size());
    for (const char c : kept) {
        const auto byte = static_cast<unsigned char>(c);
        if (c == '\\') {
            out += "\\\\";
        } else if (c == '\n') {
            out += "\\n";
        } else if (c == '\r') {
            out += "\\r";
        } else if (c == '\t') {
            out += "\\t";
        } else if (byte < 0x20 || byte >= 0x7f) {
            char escaped[5];
            std::snprintf(escaped, sizeof(escaped), "\\x%02x", byte);
            out += escaped;
        } else {
            out += c;
        }
    }
    if (kept.size() < value.size()) out += "...(" + std::to_string(value.size()) + " bytes)";
    return out;
}

}  // namespace lf
