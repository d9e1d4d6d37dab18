// OpenEXR and PNG files. EXR keeps every channel as float32 plus header attributes saying how
// the image was made; PNG is an 8-bit sRGB preview of R,G,B (exposure, then a tone curve).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <variant>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/image.h"
#include "lf/core/tone_map.h"

namespace lf {

// OpenEXR's standard `chromaticities` attribute: CIE 1931 xy of the RGB primaries and of the
// white point (an RGB of (1, 1, 1)).
struct ExrChromaticities {
    float red_x, red_y, green_x, green_y, blue_x, blue_y, white_x, white_y;
    bool operator==(const ExrChromaticities&) const = default;
};
// ITU-R BT.709 (= sRGB) primaries with the D65 white: lightfarm's RGB.
inline constexpr ExrChromaticities kRec709Chromaticities{0.64f, 0.33f, 0.30f,   0.60f,
                                                         0.15f, 0.06f, 0.3127f, 0.3290f};

// A header attribute: float only where OpenEXR's standard attributes are typed float
// (`whiteLuminance`); lightfarm's own numbers are double.
using ExrAttribute = std::variant<std::string, int, double, float, ExrChromaticities>;
using ExrAttributes = std::map<std::string, ExrAttribute>;

struct ExrFile {
    Image image;
    ExrAttributes attributes;  // those of the types above; others (boxes, vectors) are skipped
};

absl::Status WriteExr(const std::string& path, const Image& image, const ExrAttributes& attributes);
absl::StatusOr<ExrFile> ReadExr(const std::string& path);

// Linear [0, 1] to the sRGB transfer curve in 8 bits; clamped, NaN as 0.
uint8_t EncodeSrgb8(float linear);

struct PngOptions {
    double exposure = 0;  // EV: R,G,B are scaled by 2^exposure first
    ToneCurve tone = ToneCurve::kClamp;
};

// R,G,B times 2^exposure, through the tone curve, sRGB-encoded in 8 bits per channel.
absl::Status WritePng(const std::string& path, const Image& image, const PngOptions& options = {});
// The same PNG in memory, for a server that answers with it.
absl::StatusOr<std::string> EncodePng(const Image& image, const PngOptions& options = {});

}  // namespace lf
