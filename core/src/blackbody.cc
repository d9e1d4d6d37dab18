#include "lf/core/blackbody.h"

#include <algorithm>
#include <cmath>

namespace lf {

namespace {

// Planck's law: spectral radiance in W m^-2 sr^-1 per metre of wavelength at wavelength
// kCie1931FirstNm + i nm. expm1 keeps the Wien tail exact where e^x - 1 would round.
double PlanckAtCieRow(int i, double kelvin) {
    constexpr double kH = 6.62607015e-34, kC = 299792458, kK = 1.380649e-23;  // SI, exact
    const double l = (kCie1931FirstNm + i) * 1e-9;
    return 2 * kH * kC * kC / (std::pow(l, 5) * std::expm1(kH * kC / (l * kK * kelvin)));
}

}  // namespace

Xyz BlackbodyXyz(double kelvin) {
    // The 1 nm table is summed as the CIE's own practice (CIE 15:2004 7.2), a sum over its rows;
    // constant factors cancel in the normalisation.
    Xyz sum{0, 0, 0};
    for (int i = 0; i < kCie1931Count; ++i) {
        const double planck = PlanckAtCieRow(i, kelvin);
        sum.x += planck * kCie1931[size_t(i)].x;
        sum.y += planck * kCie1931[size_t(i)].y;
        sum.z += planck * kCie1931[size_t(i)].z;
    }
    return {sum.x / sum.y, 1, sum.z / sum.y};
}

double BlackbodyLuminance(double kelvin) {
    double sum = 0;
    for (int i = 0; i < kCie1931Count; ++i)
        sum += PlanckAtCieRow(i, kelvin) * kCie1931[size_t(i)].y;
    return 683 * sum * 1e-9;  // 1 nm steps
}

Rgb BlackbodyRgb(double kelvin) {
    const Xyz c = BlackbodyXyz(kelvin);
    // XYZ to linear Rec.709 / sRGB primaries with the D65 white (IEC 61966-2-1).
    const double rgb[3] = {3.2404542 * c.x - 1.5371385 * c.y - 0.4985314 * c.z,
                           -0.9692660 * c.x + 1.8760108 * c.y + 0.0415560 * c.z,
                           0.0556434 * c.x - 0.2040259 * c.y + 1.0572252 * c.z};
    double clipped[3];
    for (int i = 0; i < 3; ++i) clipped[i] = std::max(0.0, rgb[i]);
    // Normalised by the Rec.709 weights the renderer's photometry uses, so Y = 1 to rounding.
    const double y = 0.2126 * clipped[0] + 0.7152 * clipped[1] + 0.0722 * clipped[2];
    return {float(clipped[0] / y), float(clipped[1] / y), float(clipped[2] / y)};
}

}  // namespace lf
