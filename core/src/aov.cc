#include "lf/core/aov.h"

#include <array>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"

namespace lf {

namespace {
constexpr std::array<std::pair<const char*, uint32_t>, 4> kAovNames = {
    {{"albedo", kAovAlbedo},
     {"normal", kAovNormal},
     {"depth", kAovDepth},
     {"illuminance", kAovIlluminance}}};
}  // namespace

absl::StatusOr<uint32_t> ParseAovList(std::string_view list) {
    uint32_t aovs = 0;
    const absl::string_view text(list.data(), list.size());
    for (absl::string_view name : absl::StrSplit(text, ',', absl::SkipWhitespace())) {
        name = absl::StripAsciiWhitespace(name);
        if (name == "all") {
            aovs |= kAllAovs;
            continue;
        }
        bool known = false;
        for (const auto& [aov_name, flag] : kAovNames) {
            if (name != aov_name) continue;
            aovs |= flag;
            known = true;
        }
        if (!known) {
            return absl::InvalidArgumentError(absl::StrCat(
                "unknown AOV \"", name, "\"; expected albedo, normal, depth, illuminance or all"));
        }
    }
    return aovs;
}

std::string AovListName(uint32_t aovs) {
    std::string out;
    for (const auto& [name, flag] : kAovNames) {
        if (aovs & flag) absl::StrAppend(&out, out.empty() ? "" : ",", name);
    }
    return out;
}

}  // namespace lf
