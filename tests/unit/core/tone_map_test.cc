// The preview's tone curves (lf/core/tone_map.h): clamp leaves radiance alone, filmic is
// Narkowicz's ACES fit, checked against its closed form and the properties a tone curve needs.
#include "lf/core/tone_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace lf {
namespace {

// The published fit, in double: x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14).
double Aces(double x) { return x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14); }

TEST(ToneMap, NamesRoundTripAndUnknownOnesAreRefused) {
    for (ToneCurve c : {ToneCurve::kClamp, ToneCurve::kFilmic}) {
        EXPECT_EQ(ToneCurveFromName(ToneCurveName(c)), c);
    }
    EXPECT_FALSE(ToneCurveFromName("aces"));
    EXPECT_FALSE(ToneCurveFromName(""));
}

TEST(ToneMap, ClampLeavesValuesToTheEncoder) {
    for (float v : {0.0f, 0.25f, 1.0f, 3.5f, -1.0f}) {
        EXPECT_EQ(ApplyToneCurve(ToneCurve::kClamp, v), v);
    }
}

TEST(ToneMap, FilmicIsTheNarkowiczFit) {
    for (double x : {0.01, 0.18, 0.5, 1.0, 2.0, 5.0}) {
        EXPECT_NEAR(ApplyToneCurve(ToneCurve::kFilmic, float(x)), Aces(x), 1e-6) << x;
    }
    EXPECT_NEAR(ApplyToneCurve(ToneCurve::kFilmic, 1.0f), 2.54 / 3.16, 1e-6);
}

TEST(ToneMap, FilmicMapsZeroToZeroAndIsMonotone) {
    EXPECT_EQ(ApplyToneCurve(ToneCurve::kFilmic, 0.0f), 0.0f);
    float previous = 0;
    // Log-spaced from 1e-6 to 1e4: shadows, midtones, highlights and far past white.
    for (int i = 0; i <= 1000; ++i) {
        const float x = float(std::pow(10.0, -6.0 + 10.0 * i / 1000));
        const float y = ApplyToneCurve(ToneCurve::kFilmic, x);
        EXPECT_GE(y, previous) << x;
        EXPECT_LE(y, 1.0f) << x;
        previous = y;
    }
}

TEST(ToneMap, FilmicCompressesHighlightsBelowWhite) {
    // The curve reaches 1 where 0.08 x^2 - 0.56 x - 0.14 = 0.
    const double white = (0.56 + std::sqrt(0.56 * 0.56 + 4 * 0.08 * 0.14)) / 0.16;
    EXPECT_NEAR(white, 7.24, 0.01);
    for (double x = 1.0; x < white - 0.01; x += 0.05) {
        const float y = ApplyToneCurve(ToneCurve::kFilmic, float(x));
        EXPECT_LT(y, 1.0f) << x;
        EXPECT_GT(y, 0.8f) << x;  // and keeps them apart: above f(1)
    }
    // Where the clamp curve clips everything above 1 to white, filmic keeps a gradient: 1, 2 and
    // 4 stay distinguishable.
    EXPECT_LT(ApplyToneCurve(ToneCurve::kFilmic, 1.0f), ApplyToneCurve(ToneCurve::kFilmic, 2.0f));
    EXPECT_LT(ApplyToneCurve(ToneCurve::kFilmic, 2.0f), ApplyToneCurve(ToneCurve::kFilmic, 4.0f));
    EXPECT_EQ(ApplyToneCurve(ToneCurve::kFilmic, 100.0f), 1.0f);
}

TEST(ToneMap, FilmicTakesInvalidValuesToBlackAndInfinityToWhite) {
    EXPECT_EQ(ApplyToneCurve(ToneCurve::kFilmic, -0.5f), 0.0f);
    EXPECT_EQ(ApplyToneCurve(ToneCurve::kFilmic, std::numeric_limits<float>::quiet_NaN()), 0.0f);
    EXPECT_EQ(ApplyToneCurve(ToneCurve::kFilmic, std::numeric_limits<float>::infinity()), 1.0f);
}

}  // namespace
}  // namespace lf
