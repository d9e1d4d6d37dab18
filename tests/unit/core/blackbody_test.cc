// Black-body colours against the published Planckian locus (CIE 1931 chromaticities), their
// luminance, and the order of colours with temperature.
#include "lf/core/blackbody.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

// Chromaticities are published to 4 decimals (rounding: 5e-5). The table stops at 380 and
// 780 nm where the CIE's runs 360-830 nm; the observer there is below 1.5e-3 of its peak, and
// the missing tails move x and y by about 3e-5 (illuminant A here: 0.447538, 0.407437). 1e-4 holds
// both with room, and a wrong table, constant or matrix misses it by far more (a table off by 1 nm
// moves illuminant A's x by 6e-4).
constexpr double kTolerance = 1e-4;

void ExpectChromaticity(double kelvin, double x, double y) {
    const Xyz c = BlackbodyXyz(kelvin);
    const double sum = c.x + c.y + c.z;
    EXPECT_NEAR(c.x / sum, x, kTolerance) << kelvin << " K";
    EXPECT_NEAR(c.y / sum, y, kTolerance) << kelvin << " K";
    EXPECT_DOUBLE_EQ(c.y, 1);
}

TEST(Blackbody, IlluminantAIsOnThePlanckianLocus) {
    // CIE standard illuminant A is a black body at 2856 K (CIE 15:2004: x = 0.44757, y = 0.40745).
    ExpectChromaticity(2856, 0.44757, 0.40745);
}

TEST(Blackbody, MatchesPublishedPlanckianLocus) {
    // The Planckian locus in CIE 1931 (x, y) as the colorimetry literature tabulates it (e.g.
    // Wyszecki & Stiles, Color Science), to 4 decimals.
    ExpectChromaticity(6500, 0.3135, 0.3237);
    ExpectChromaticity(5000, 0.3451, 0.3516);
    ExpectChromaticity(10000, 0.2807, 0.2884);
}

TEST(Blackbody, Rec709LuminanceIsOne) {
    for (double k = kMinBlackbodyK; k <= kMaxBlackbodyK; k *= 1.25) {
        const Rgb c = BlackbodyRgb(k);
        EXPECT_NEAR(0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b, 1, 3e-7) << k << " K";
        EXPECT_GE(c.r, 0);
        EXPECT_GE(c.g, 0);
        EXPECT_GE(c.b, 0);
    }
}

TEST(Blackbody, WhiteNearD65AndRedderWhenCooler) {
    // D65's correlated colour temperature is 6504 K, close to (not on) the locus: about white.
    const Rgb d65 = BlackbodyRgb(6504);
    EXPECT_NEAR(d65.r / d65.b, 1, 0.1);
    double previous_x = 1, previous_red = 1e9;
    for (double k = kMinBlackbodyK; k <= kMaxBlackbodyK; k += 250) {
        const Xyz xyz = BlackbodyXyz(k);
        const double x = xyz.x / (xyz.x + xyz.y + xyz.z);
        // Along the locus, x falls strictly with temperature; so does red against green (blue
        // is clipped to 0 below about 1900 K, so it cannot order the coolest ones).
        const Rgb c = BlackbodyRgb(k);
        EXPECT_LT(x, previous_x) << k << " K";
        EXPECT_LT(c.r / c.g, previous_red) << k << " K";
        previous_x = x;
        previous_red = c.r / c.g;
    }
}

// 683 Int V B dlambda by a sum of its own: Planck's law in the CODATA 2018 radiation constants
// (c1L = 2 h c^2, c2 = h c / k) at the observer's 1 nm rows.
TEST(Blackbody, LuminanceIsTheLuminousIntegralOfPlanck) {
    constexpr double kC1L = 1.191042972e-16, kC2 = 1.438776877e-2;
    for (double kelvin : {1500.0, 3000.0, 6500.0}) {
        double sum = 0;
        for (int nm = kCie1931FirstNm; nm <= kCie1931LastNm; ++nm) {
            const double l = nm * 1e-9;
            sum += kC1L / std::pow(l, 5) / std::expm1(kC2 / (l * kelvin)) *
                   kCie1931[size_t(nm - kCie1931FirstNm)].y * 1e-9;
        }
        EXPECT_NEAR(BlackbodyLuminance(kelvin), 683 * sum, 1e-6 * 683 * sum) << kelvin << " K";
    }
    // The candela of 1948-1979: a black body at the freezing point of platinum (2042 K on
    // ITS-90) has 60 cd/cm^2.
    EXPECT_NEAR(BlackbodyLuminance(2042), 6e5, 0.01 * 6e5);
    // Hotter is brighter, by orders of magnitude.
    EXPECT_GT(BlackbodyLuminance(3000), 1000 * BlackbodyLuminance(1500));
}

}  // namespace
}  // namespace lf
