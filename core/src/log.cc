#include "lf/core/log.h"

#include <algorithm>
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
    out.reserve(std::min(value.size(), max_bytes));
    size_t used = 0;  // bytes of `value` escaped into `out`
    for (; used < value.size(); ++used) {
        const char c = value[used];
        const auto byte = static_cast<unsigned char>(c);
        char escaped[5] = {c, 0};
        if (c == '\\' || c == '\n' || c == '\r' || c == '\t') {
            escaped[0] = '\\';
            escaped[1] = c == '\\' ? '\\' : c == '\n' ? 'n' : c == '\r' ? 'r' : 't';
        } else if (byte < 0x20 || byte >= 0x7f) {
            std::snprintf(escaped, sizeof(escaped), "\\x%02x", byte);
        }
        const std::string_view piece(escaped);
        // The bound is on the escaped text: a value of newlines stays as short as any other.
        if (out.size() + piece.size() > max_bytes) break;
        out += piece;
    }
    if (used < value.size()) out += "...(" + std::to_string(value.size()) + " bytes)";
    return out;
}

}  // namespace lf
