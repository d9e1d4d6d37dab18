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

TEST(ImageError, LogLogSlopeOfAPowerLaw) {
    std::vector<std::pair<double, double>> points;
    for (double t : {0.1, 1.0, 3.0, 40.0}) points.push_back({t, 7 * std::pow(t, -0.5)});
    EXPECT_NEAR(LogLogSlope(points).value(), -0.5, 1e-12);
    EXPECT_FALSE(LogLogSlope({{1, 1}}).ok());
    EXPECT_FALSE(LogLogSlope({{1, 1}, {1, 2}}).ok());
    EXPECT_FALSE(LogLogSlope({{1, 1}, {2, 0}}).ok());
}

}  // namespace
}  // namespace lf
