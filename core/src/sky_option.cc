#include "lf/core/sky_option.h"

#include <cmath>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace lf {
namespace {
constexpr double kMaxSkyRadiance = 1e10;  // as a JSON environment's radiance
}  // namespace

absl::StatusOr<SkyOption> ParseSkyOption(const std::string& text) {
    const std::string expected =
        "expected white, R,G,B or a number (radiance, W m^-2 sr^-1, each 0 to 1e10), or a "
        "Radiance HDR or OpenEXR lat-long map file";
    if (text.empty()) return absl::InvalidArgumentError("--sky \"\": " + expected);
    if (text == "white") return SkyOption{};
    if (text.find_first_not_of("0123456789+-.,eE ") != std::string::npos) {
        return SkyOption{Rgb(1.0f), text};
    }
    const std::vector<std::string> parts = absl::StrSplit(text, ',');
    std::vector<double> values;
    for (const std::string& part : parts) {
        double v = 0;
        if (!absl::SimpleAtod(part, &v) || !std::isfinite(v) || v < 0 || v > kMaxSkyRadiance) {
            return absl::InvalidArgumentError(
                absl::StrCat("--sky \"", text, "\": \"", part, "\" is not a radiance; ", expected));
        }
        values.push_back(v);
    }
    if (values.size() == 1) return SkyOption{Rgb(float(values[0])), ""};
    if (values.size() == 3) {
        return SkyOption{Rgb(float(values[0]), float(values[1]), float(values[2])), ""};
    }
    return absl::InvalidArgumentError(
        absl::StrCat("--sky \"", text, "\": ", values.size(), " numbers; ", expected));
}

}  // namespace lf
