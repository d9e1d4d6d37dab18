// False-colour pictures (lf/core/false_color.h): a ramp that brightens monotonically, values
// placed on a logarithmic scale, the robust decade range, a legend drawn under the picture, and
// bad specifications refused with what is wrong.
#include "lf/core/false_color.h"

#include <gtest/gtest.h>

#include <cmath>

#include "absl/strings/match.h"
#include "lf/core/aov.h"

namespace lf {
namespace {

double Lightness(const std::array<uint8_t, 3>& c) {
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

TEST(FalseColor, RampBrightensMonotonicallyFromDarkBlueToYellow) {
    // Brighter at every step of 1/32; at steps of 1/256 never darker by more than rounding to
    // 8 bits can make it (half a code value a channel on either side).
    for (int i = 1; i <= 256; ++i) {
        EXPECT_GE(Lightness(FalseColorRamp(i / 256.0)),
                  Lightness(FalseColorRamp((i - 1) / 256.0)) - 1.0)
            << "t = " << i / 256.0;
    }
    for (int i = 1; i <= 32; ++i) {
        EXPECT_GT(Lightness(FalseColorRamp(i / 32.0)), Lightness(FalseColorRamp((i - 1) / 32.0)))
            << "t = " << i / 32.0;
    }
    const auto low = FalseColorRamp(0), high = FalseColorRamp(1);
    EXPECT_GT(low[2], low[0]);    // blue-violet at the bottom
    EXPECT_GT(high[0], high[2]);  // yellow at the top
    EXPECT_EQ(FalseColorRamp(-3), low);
    EXPECT_EQ(FalseColorRamp(7), high);
}

TEST(FalseColor, PlacesValuesOnALogarithmicScale) {
    EXPECT_DOUBLE_EQ(FalseColorPosition(1, 1, 100), 0);
    EXPECT_DOUBLE_EQ(FalseColorPosition(10, 1, 100), 0.5);
    EXPECT_DOUBLE_EQ(FalseColorPosition(100, 1, 100), 1);
    EXPECT_NEAR(FalseColorPosition(30, 10, 1000), std::log10(3.0) / 2, 1e-12);
    EXPECT_EQ(FalseColorPosition(0.5, 1, 100), 0);  // clamped below
    EXPECT_EQ(FalseColorPosition(1e6, 1, 100), 1);  // and above
    EXPECT_EQ(FalseColorPosition(0, 1, 100), 0);
    EXPECT_EQ(FalseColorPosition(std::nan(""), 1, 100), 0);
}

TEST(FalseColor, RobustRangeRoundsPercentilesOutToDecades) {
    std::vector<float> values;
    for (int i = 0; i < 1000; ++i) values.push_back(2 + 0.5f * float(i));  // 2 .. 501.5
    values[0] = 1e-9f;                                                     // outliers: ignored
    values[1] = 1e9f;
    values.push_back(0);
    values.push_back(-5);
    EXPECT_EQ(RobustDecadeRange(values), std::make_pair(1.0, 1000.0));
    const std::vector<float> flat(10, 50.0f);
    EXPECT_EQ(RobustDecadeRange(flat), std::make_pair(10.0, 100.0));
    EXPECT_EQ(RobustDecadeRange(std::vector<float>(4, 0.0f)), std::make_pair(1.0, 10.0));
}

TEST(FalseColor, DrawsThePictureAndALegendUnderIt) {
    constexpr int kWidth = 160, kHeight = 20;
    std::vector<float> values(kWidth * kHeight);
    for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) values[size_t(y) * kWidth + x] = float(x + 1);
    }
    const Rgb8Picture picture =
        DrawFalseColor(values, kWidth, kHeight, FalseColorUnit::kLux, 1, 100).value();
    ASSERT_EQ(picture.width, kWidth);
    ASSERT_EQ(picture.height, kHeight + kFalseColorLegendRows);
    const auto at = [&](int x, int y) {
        const uint8_t* p = &picture.rgb[(size_t(y) * kWidth + x) * 3];
        return std::array<uint8_t, 3>{p[0], p[1], p[2]};
    };
    EXPECT_EQ(at(0, 0), FalseColorRamp(0));                     // 1 lux
    EXPECT_EQ(at(9, 5), FalseColorRamp(0.5));                   // 10 lux
    EXPECT_EQ(at(kWidth - 1, kHeight - 1), FalseColorRamp(1));  // 160: clamped
    // The legend's bar runs through the ramp from its left end.
    EXPECT_EQ(at(4, kHeight + 8), FalseColorRamp(0));
    EXPECT_GT(Lightness(at(100, kHeight + 8)), Lightness(at(20, kHeight + 8)));
    // Ink (white) in the tick and number rows and beside the bar (the unit).
    int ink_numbers = 0, ink_unit = 0;
    for (int y = kHeight + 14; y < kHeight + kFalseColorLegendRows; ++y) {
        for (int x = 0; x < kWidth; ++x)
            ink_numbers += at(x, y) == std::array<uint8_t, 3>{255, 255, 255};
    }
    for (int y = kHeight; y < kHeight + 14; ++y) {
        for (int x = kWidth - 30; x < kWidth; ++x) {
            ink_unit += at(x, y) == std::array<uint8_t, 3>{255, 255, 255};
        }
    }
    EXPECT_GT(ink_numbers, 20);
    EXPECT_GT(ink_unit, 10);
    EXPECT_FALSE(DrawFalseColor(values, kWidth, kHeight + 1, FalseColorUnit::kLux, 1, 100).ok());
    EXPECT_FALSE(DrawFalseColor(values, kWidth, kHeight, FalseColorUnit::kLux, 10, 1).ok());
}

TEST(FalseColor, ParsesUnitsAndRangesAndRefusesBadOnes) {
    EXPECT_EQ(ParseFalseColor("lux")->unit, FalseColorUnit::kLux);
    EXPECT_FALSE(ParseFalseColor("lux")->range);
    const FalseColorSpec nits = ParseFalseColor("nits:0.1:1000").value();
    EXPECT_EQ(nits.unit, FalseColorUnit::kNits);
    EXPECT_EQ(nits.range, std::make_pair(0.1, 1000.0));
    for (const char* bad : {"furlongs", "lux:10:1", "lux:0:10", "lux:-1:10", "lux:1", "lux:a:b",
                            "nits:1:inf", "lux:1:10:100", ""}) {
        const absl::StatusOr<FalseColorSpec> s = ParseFalseColor(bad);
        ASSERT_FALSE(s.ok()) << bad;
        EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument) << bad;
        EXPECT_TRUE(absl::StrContains(s.status().message(), "--false-color")) << s.status();
    }
    EXPECT_TRUE(absl::StrContains(ParseFalseColor("furlongs").status().message(), "lux or nits"));
}

TEST(FalseColor, LuxNeedsTheIlluminanceChannelAndNitsAre683TimesLuminance) {
    Image image(2, 1);
    for (const char* c : {"R", "G", "B"}) image.Channel(c) = {1, 0.5f};
    const absl::StatusOr<std::vector<float>> lux = FalseColorValues(image, FalseColorUnit::kLux);
    ASSERT_EQ(lux.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_TRUE(absl::StrContains(lux.status().message(), "--aov illuminance"));
    const std::vector<float> nits = FalseColorValues(image, FalseColorUnit::kNits).value();
    EXPECT_NEAR(nits[0], 683, 1e-3);
    EXPECT_NEAR(nits[1], 341.5, 1e-3);
    image.Channel(kAovIlluminanceChannel) = {5, 7};
    EXPECT_EQ(FalseColorValues(image, FalseColorUnit::kLux).value(), std::vector<float>({5, 7}));
}

TEST(FalseColor, PathSitsBesideTheExr) {
    EXPECT_EQ(FalseColorPath("out.exr"), "out.falsecolor.png");
    EXPECT_EQ(FalseColorPath("renders.v2/out"), "renders.v2/out.falsecolor.png");
    EXPECT_EQ(FalseColorPath("/tmp/a.b.exr"), "/tmp/a.b.falsecolor.png");
}

}  // namespace
}  // namespace lf
