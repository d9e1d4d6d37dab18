#include "lf/core/plural.h"

namespace lf {

std::string Plural(int64_t count, std::string_view noun) {
    std::string out = std::to_string(count);
    out += ' ';
    out += noun;
    if (count == 1) return out;
    const auto ends = [&](std::string_view end) {
        return noun.size() >= end.size() && noun.substr(noun.size() - end.size()) == end;
    };
    out += ends("s") || ends("x") || ends("z") || ends("ch") || ends("sh") ? "es" : "s";
    return out;
}

}  // namespace lf
