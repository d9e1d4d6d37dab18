// The CIE 1931 2-degree standard observer's colour-matching functions x̄, ȳ, z̄ (tabulated in
// cie_1931.cc, with its source): what turns a spectrum into CIE XYZ.
#pragma once

#include <array>

namespace lf {

// CIE XYZ tristimulus values.
struct Xyz {
    double x, y, z;
};

// kCie1931[i] is the observer at wavelength kCie1931FirstNm + i nanometres.
inline constexpr int kCie1931FirstNm = 380, kCie1931LastNm = 780;
inline constexpr int kCie1931Count = kCie1931LastNm - kCie1931FirstNm + 1;
extern const std::array<Xyz, kCie1931Count> kCie1931;

}  // namespace lf
