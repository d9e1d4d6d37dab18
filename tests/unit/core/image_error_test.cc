// The convergence metrics against hand-computed values, and the half-buffer error estimate
// against the spread it estimates.
#include "lf/core/image_error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

Image Constant(int w, int h, float value) {
    Image image(w, h);
    for (const char* c : {"R", "G", "B", "A.R", "A.G", "A.B", "B.R", "B.G", "B.B"}) {
        image.Channel(c).assign(size_t(w) * h, value);
    }
    return image;
}

TEST(ImageError, MetricsMatchTheirDefinitions) {
    const Image reference = Constant(2, 1, 0.5f);
    Image image = Constant(2, 1, 0.5f);
    image.Channel("R")[0] = 1.0f;  // one of six values off by 0.5
    const ImageError e = CompareImages(image, reference).value();
    EXPECT_DOUBLE_EQ(e.rmse, std::sqrt(0.25 / 6));
    EXPECT_DOUBLE_EQ(e.relmse, 0.25 / (0.25 + kRelativeErrorEpsilon) / 6);
    EXPECT_DOUBLE_EQ(e.smape, 0.5 / (1.5 + kRelativeErrorEpsilon) / 6);
    EXPECT_EQ(CompareImages(reference, reference).value().rmse, 0);
}

TEST(ImageError, RegionCountsItsPixelsOnly) {
    const Image reference = Constant(4, 3, 0.5f);
    Image image = Constant(4, 3, 0.5f);
    image.Channel("G")[size_t(1 * 4 + 2)] = 1.5f;  // pixel (2, 1): inside the region
    image.Channel("R")[0] = 9.0f;                  // pixel (0, 0): outside it
    const ImageError e = CompareImageRegion(image, reference, PixelRect{2, 1, 2, 2}).value();
    EXPECT_DOUBLE_EQ(e.rmse, std::sqrt(1.0 / 12));  // one of 4 px x 3 channels off by 1
    EXPECT_GT(CompareImages(image, reference).value().rmse, e.rmse);
    EXPECT_FALSE(CompareImageRegion(image, reference, PixelRect{3, 0, 2, 1}).ok());
    EXPECT_FALSE(CompareImageRegion(image, reference, PixelRect{0, 0, 0, 0}).ok());
    EXPECT_FALSE(CompareImageRegion(image, reference, PixelRect{-1, 0, 1, 1}).ok());
}

TEST(ImageError, RefusesMismatchedImages) {
    EXPECT_FALSE(CompareImages(Constant(2, 1, 0), Constant(1, 2, 0)).ok());
    EXPECT_FALSE(CompareImages(Image(1, 1), Constant(1, 1, 0)).ok());
    EXPECT_FALSE(EstimatedMse(Image(1, 1)).ok());
}

TEST(ImageError, HalfBufferEstimateIsTheVarianceOfTheMean) {
    // A = m + d, B = m - d: the mean is m and ((A - B) / 2)^2 = d^2 exactly.
    Image image = Constant(4, 4, 0.3f);
    for (const char* c : {"A.R", "A.G", "A.B"}) image.Channel(c).assign(16, 0.3f + 0.125f);
    for (const char* c : {"B.R", "B.G", "B.B"}) image.Channel(c).assign(16, 0.3f - 0.125f);
    EXPECT_NEAR(EstimatedMse(image).value(), 0.125 * 0.125, 1e-9);
}

// A = x + d, B = x - d per pixel, so ((A - B) / 2)^2 = d^2 and the estimate is analytic. Fifteen
// pixels of 0.5 off by 1 %, one light-edge pixel of 8 off by 25 %: the relMSE estimate is about
// the typical pixel's, while the whole image's RMS against its mean radiance is that one
// pixel's absolute error. The bright pixel is bright in both halves, so it is measured against
// the dimmer half, 6, not against its dim neighbours.
TEST(ImageError, RelMseEstimateIsThePerPixelRelativeVariance) {
    constexpr float kValue = 0.5f, kSpread = 0.005f, kEdge = 8.0f, kEdgeSpread = 2.0f;
    Image image = Constant(4, 4, kValue);
    for (const char* c : {"A.R", "A.G", "A.B"}) image.Channel(c).assign(16, kValue + kSpread);
    for (const char* c : {"B.R", "B.G", "B.B"}) image.Channel(c).assign(16, kValue - kSpread);
    for (const char* c : {"R", "G", "B"}) image.Channel(c)[5] = kEdge;
    for (const char* c : {"A.R", "A.G", "A.B"}) image.Channel(c)[5] = kEdge + kEdgeSpread;
    for (const char* c : {"B.R", "B.G", "B.B"}) image.Channel(c)[5] = kEdge - kEdgeSpread;

    const double d = double(kValue + kSpread) - kValue;  // kSpread as the floats hold it
    const double relmse =
        (15 * d * d / (double(kValue) * kValue + kRelativeErrorEpsilon) +
         double(kEdgeSpread) * kEdgeSpread /
             (double(kEdge - kEdgeSpread) * (kEdge - kEdgeSpread) + kRelativeErrorEpsilon)) /
        16;
    EXPECT_NEAR(EstimatedRelMse(image).value(), relmse, 1e-9 * relmse);
    EXPECT_LT(std::sqrt(relmse), 0.1);
    const double mean = (15 * double(kValue) + kEdge) / 16;
    const double rms = std::sqrt((15 * d * d + double(kEdgeSpread) * kEdgeSpread) / 16);
    EXPECT_NEAR(EstimatedRelativeError(image).value(), rms / (mean + kRelativeErrorFloor), 1e-9);
    EXPECT_GT(EstimatedRelativeError(image).value(), 0.5);

    // A black pixel with equal halves adds nothing; a missing R refuses.
    Image black = Constant(1, 1, 0);
    EXPECT_EQ(EstimatedRelMse(black).value(), 0);
    Image halves_only(1, 1);
    for (const char* c : {"A.R", "A.G", "A.B", "B.R", "B.G", "B.B"}) {
        halves_only.Channel(c).assign(1, 0);
    }
    EXPECT_TRUE(EstimatedMse(halves_only).ok());
    EXPECT_FALSE(EstimatedRelMse(halves_only).ok());
}

TEST(ImageError, LogLogSlopeOfAPowerLaw) {
    std::vector<std::pair<double, double>> points;
    for (double t : {0.1, 1.0, 3.0, 40.0}) points.push_back({t, 7 * std::pow(t, -0.5)});
    EXPECT_NEAR(LogLogSlope(points).value(), -0.5, 1e-12);
    EXPECT_FALSE(LogLogSlope({{1, 1}}).ok());
    EXPECT_FALSE(LogLogSlope({{1, 1}, {1, 2}}).ok());
    EXPECT_FALSE(LogLogSlope({{1, 1}, {2, 0}}).ok());
}

// A firefly: one sample of 100 in one half of a pixel of 0.5 among pixels of 0.5. Its own mean,
// 25.4, would divide its error away (a term of about 1); the other half and the neighbours,
// which do not hold it, put it at 0.5, as the reference would. Beside a light (neighbours of 17)
// a dim pixel keeps its own value, so the light does not hide its noise.
TEST(ImageError, RelMseEstimateDoesNotLetAFireflyDivideItselfAway) {
    constexpr float kValue = 0.5f, kFirefly = 100.0f;
    Image image = Constant(3, 3, kValue);
    for (const char* c : {"A.R", "A.G", "A.B"}) image.Channel(c)[4] = (kFirefly + kValue) / 2;
    for (const char* c : {"R", "G", "B"}) image.Channel(c)[4] = (kFirefly + 3 * kValue) / 4;
    const double half = ((kFirefly + kValue) / 2 - kValue) / 2;
    const double firefly = half * half / (double(kValue) * kValue + kRelativeErrorEpsilon) / 9;
    EXPECT_NEAR(EstimatedRelMse(image).value(), firefly, 1e-6 * firefly);
    EXPECT_GT(EstimatedRelMse(image).value(), 100);

    constexpr float kLight = 17.0f, kSpread = 0.05f;
    Image beside = Constant(3, 3, kLight);
    for (const char* c : {"R", "G", "B"}) beside.Channel(c)[4] = kValue;
    for (const char* c : {"A.R", "A.G", "A.B"}) beside.Channel(c)[4] = kValue + kSpread;
    for (const char* c : {"B.R", "B.G", "B.B"}) beside.Channel(c)[4] = kValue - kSpread;
    const double d = double(kValue + kSpread) - kValue;
    const double dim = d * d / (double(kValue) * kValue + kRelativeErrorEpsilon) / 9;
    EXPECT_NEAR(EstimatedRelMse(beside).value(), dim, 1e-5 * dim);
}

// A tile's stopping error is the square root of the relMSE the same pixels give as an image, so
// each pixel counts relative to itself: a bright pixel does not hide its dim neighbours' noise.
TEST(EstimatedTileError, IsTheSquareRootOfTheTilesRelMse) {
    TileSums tile(PixelRect{0, 0, 4, 2});
    for (int i = 0; i < 8; ++i) {
        // One bright, steady pixel, as a light; dim ones off by 20 %.
        const float base = i == 0 ? 20.0f : 0.2f, spread = i == 0 ? 0.0f : 0.2f;
        for (uint64_t s = 0; s < 16; ++s) {
            tile.pixels[size_t(i)].Add(s, Rgb(base * (1 + (s % 2 ? spread : -spread))));
        }
    }
    Image image(4, 2);
    image.SetTile(tile);
    const double relmse = EstimatedRelMse(image).value();
    EXPECT_NEAR(EstimatedTileError(tile), std::sqrt(relmse), 1e-6 * std::sqrt(relmse));
    // Relative to the tile's mean, the bright pixel would make the dim ones' noise look small.
    EXPECT_GT(EstimatedTileError(tile), 5 * EstimatedRelativeError(image).value());

    TileSums fresh(PixelRect{0, 0, 2, 2});
    EXPECT_EQ(EstimatedTileError(fresh), 1);  // no samples: no estimate yet
}

}  // namespace
}  // namespace lf
