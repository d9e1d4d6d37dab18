// A count and its noun as a user reads them: "1 thread", "2 threads", "1 pass", "0 passes".
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace lf {

// `noun` is singular; its plural adds "es" after s, x, z, ch and sh, else "s".
std::string Plural(int64_t count, std::string_view noun);

}  // namespace lf
