// False-colour pictures for lighting design (`render`/`fetch --false-color`): illuminance in lux
// (the `illuminance` AOV) or luminance in nits (cd/m^2 = 683 lm/W x the Rec.709 luminance of
// the radiance) mapped through a logarithmic scale onto viridis, a perceptual ramp whose
// lightness rises monotonically (so it reads in grey too), with a legend bar, decade ticks and
// their numbers and the unit drawn under the picture.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/image.h"

namespace lf {

enum class FalseColorUnit { kLux, kNits };

// What `--false-color` asks for: the quantity, and the scale's ends, or none for the image's
// robust range (RobustDecadeRange).
struct FalseColorSpec {
    FalseColorUnit unit = FalseColorUnit::kLux;
    std::optional<std::pair<double, double>> range;
};

// "lux", "nits", "lux:MIN:MAX", "nits:MIN:MAX" with 0 < MIN < MAX finite; InvalidArgument naming
// what is wrong otherwise.
absl::StatusOr<FalseColorSpec> ParseFalseColor(std::string_view text);

// The unit as the legend writes it: "lux", "cd/m2".
const char* FalseColorUnitLabel(FalseColorUnit unit);

// The ramp at t in [0, 1] (clamped), 8-bit sRGB: viridis, dark blue through green to yellow.
std::array<uint8_t, 3> FalseColorRamp(double t);

// Where `value` lies on the logarithmic scale from `min` to `max`: log(value/min)/log(max/min),
// clamped to [0, 1]; 0 for values <= 0 and NaN.
double FalseColorPosition(double value, double min, double max);

// The scale for `values`: their 1st and 99th percentiles over the positive finite ones, rounded
// out to powers of ten, at least a decade apart; [1, 10] when none is positive.
std::pair<double, double> RobustDecadeRange(std::span<const float> values);

// Ok unless `spec` maps lux and `aovs` (lf/core/aov.h flags) lacks the illuminance: then
// FailedPrecondition saying to add --aov illuminance, before a render that could not give it.
absl::Status CheckFalseColorSource(const FalseColorSpec& spec, uint32_t aovs);

// One value a pixel of `image` for `unit`: its `illuminance` channel for lux
// (FailedPrecondition saying to add --aov illuminance without it), 683 x Y(R, G, B) for nits.
absl::StatusOr<std::vector<float>> FalseColorValues(const Image& image, FalseColorUnit unit);

// An 8-bit sRGB picture, row by row.
struct Rgb8Picture {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
};

// Rows of legend under the picture.
inline constexpr int kFalseColorLegendRows = 32;

// `values` (width x height, row by row) mapped onto the ramp between min and max, then the
// legend: the ramp as a bar, a tick and number at every power of ten in the range (numbers that
// would overlap are left out) and the unit at the bar's right. InvalidArgument for a size that
// does not match, or a bad range.
absl::StatusOr<Rgb8Picture> DrawFalseColor(std::span<const float> values, int width, int height,
                                           FalseColorUnit unit, double min, double max);

// `path` for `exr_path`: its extension (if any) replaced by ".falsecolor.png" (out.exr ->
// out.falsecolor.png).
std::string FalseColorPath(const std::string& exr_path);

// The false-colour PNG of `image` as `spec` says, at `path`.
absl::Status WriteFalseColorPng(const std::string& path, const Image& image,
                                const FalseColorSpec& spec);

}  // namespace lf
