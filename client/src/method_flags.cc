#include "lf/client/method_flags.h"

namespace lf {

namespace {
constexpr const char* kAuto = "auto";
}  // namespace

std::string MethodFlagError(const std::string& method, bool allow_auto) {
    if (allow_auto && method == kAuto) return "";
    const absl::StatusOr<Method> parsed = ParseMethod(method);
    if (parsed.ok()) return "";
    std::string message(parsed.status().message());
    const std::string expected = "expected one of ";
    if (const size_t at = message.find(expected); allow_auto && at != std::string::npos) {
        message.insert(at + expected.size(), "auto, ");
    }
    return message;
}

std::optional<Method> MethodOfFlag(const std::string& method) {
    if (method == kAuto) return std::nullopt;
    return FindMethod(method);
}

}  // namespace lf
