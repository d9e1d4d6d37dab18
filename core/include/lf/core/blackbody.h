// The colour of a black body (`temperature_k` in scene files): Planck's law integrated against
// the CIE 1931 2-degree observer, converted to linear Rec.709 and normalised to luminance 1.
#pragma once

#include "lf/core/cie_1931.h"
#include "lf/core/rgb.h"

namespace lf {

// Temperatures a scene may give, in kelvin: candle flame to blue sky.
inline constexpr double kMinBlackbodyK = 1000, kMaxBlackbodyK = 40000;

// CIE XYZ of a black body at `kelvin` (> 0), scaled to Y = 1.
Xyz BlackbodyXyz(double kelvin);

// Linear Rec.709 (D65 white) of a black body at `kelvin`, with Rec.709 luminance
// 0.2126 R + 0.7152 G + 0.0722 B = 1. Below about 1900 K the locus leaves the Rec.709 gamut
// (blue would be negative): a negative channel is clipped to 0 before normalising.
Rgb BlackbodyRgb(double kelvin);

// The luminance of a black body at `kelvin` (> 0) in cd/m^2: 683 lm/W times the integral of
// Planck's spectral radiance against the photopic V = y-bar (1 nm steps, 380-780 nm). With
// BlackbodyRgb, BlackbodyRgb(T) * BlackbodyLuminance(T) / 683 is its radiance in the renderer's
// absolute units.
double BlackbodyLuminance(double kelvin);

}  // namespace lf
