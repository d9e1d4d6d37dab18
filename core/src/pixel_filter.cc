#include "lf/core/pixel_filter.h"

#include <array>
#include <utility>

#include "absl/strings/str_cat.h"

namespace lf {

namespace {
constexpr std::array<std::pair<PixelFilter::Type, const char*>, 3> kFilterNames = {{
    {PixelFilter::Type::kBox, "box"},
    {PixelFilter::Type::kGaussian, "gaussian"},
    {PixelFilter::Type::kBlackmanHarris, "blackman-harris"},
}};
}  // namespace

const char* PixelFilterTypeName(PixelFilter::Type type) {
    for (const auto& [t, name] : kFilterNames) {
        if (t == type) return name;
    }
    return "unknown";
}

std::optional<PixelFilter::Type> PixelFilterTypeFromName(const std::string& name) {
    for (const auto& [t, n] : kFilterNames) {
        if (name == n) return t;
    }
    return std::nullopt;
}

absl::Status CheckPixelFilter(const PixelFilter& filter) {
    if (filter.type == PixelFilter::Type::kBox) {
        if (filter.width == 1) return absl::OkStatus();
        return absl::InvalidArgumentError(
            absl::StrCat("width ", filter.width, ": the box filter is one pixel wide"));
    }
    if (filter.width >= kMinFilterWidth && filter.width <= kMaxFilterWidth) {
        return absl::OkStatus();
    }
    return absl::InvalidArgumentError(absl::StrCat("width ", filter.width, ": expected ",
                                                   kMinFilterWidth, " to ", kMaxFilterWidth,
                                                   " pixels"));
}

std::string DescribePixelFilter(const PixelFilter& filter) {
    if (filter.type == PixelFilter::Type::kBox) return "box";
    return absl::StrCat(PixelFilterTypeName(filter.type), " ", filter.width, " px");
}

}  // namespace lf
