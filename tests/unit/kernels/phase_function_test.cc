// Henyey-Greenstein: its sampling against its density (chi-square), its mean cosine, its
// normalisation, and the returned pdf against the density.
#include "lf/kernels/phase_function.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "chi_square.h"
#include "lf/core/sampler.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

using testing::kPi;

const float kGs[] = {-0.7f, 0.0f, 0.3f, 0.9f};
constexpr int kNumGs = 4;
constexpr int kSamples = 1'000'000;
// An incident direction off the axes, so that the sampler's frame is not a coordinate frame.
const Vec3 kTravel = Normalize(Vec3(0.3f, -0.5f, 0.8f));

std::string Name(float g) { return "g" + std::to_string(int(std::lround(g * 10))); }

class HenyeyGreensteinTest : public ::testing::TestWithParam<float> {};

// Sampled directions binned by the angle to the direction of travel (30 equal steps) and the
// azimuth about it (12, in a frame of the test's own) against the density's integral over each
// cell; Bonferroni over the four g at 1e-3.
TEST_P(HenyeyGreensteinTest, SamplingMatchesDensity) {
    const float g = GetParam();
    constexpr int kTheta = 30, kPhi = 12;
    const Vec3d d(kTravel);
    const Vec3d x = Normalize(Cross(d, Vec3d(0, 0, 1))), y = Cross(d, x);
    std::vector<double> observed(kTheta * kPhi, 0.0), expected(observed.size(), 0.0);
    for (int i = 0; i < kSamples; ++i) {
        Sampler sampler(std::hash<std::string>{}(Name(g)), 0, 0, uint64_t(i));
        const Vec3d w(SampleHenyeyGreenstein(kTravel, g, sampler.Get2D()).wi);
        const double theta = std::atan2(Length(Cross(w, d)), Dot(w, d));
        double phi = std::atan2(Dot(w, y), Dot(w, x));
        if (phi < 0) phi += 2 * kPi;
        const int ti = std::min(int(theta / kPi * kTheta), kTheta - 1);
        const int pi = std::min(int(phi / (2 * kPi) * kPhi), kPhi - 1);
        ++observed[size_t(ti * kPhi + pi)];
    }
    for (int ti = 0; ti < kTheta; ++ti) {
        // The density is uniform in azimuth: the row's mass, 2 pi Int p dcos, split evenly.
        const double mass = testing::Integrate1D(
            [&](double c) { return 2 * kPi * HenyeyGreenstein(float(c), g); },
            std::cos((ti + 1) * kPi / kTheta), std::cos(ti * kPi / kTheta), 64);
        for (int pi = 0; pi < kPhi; ++pi) expected[size_t(ti * kPhi + pi)] = mass / kPhi * kSamples;
    }
    EXPECT_GT(testing::ChiSquareFit(observed, expected), 1e-3 / kNumGs) << Name(g);
}

// The mean cosine of the scattering angle is g, within 4 standard errors.
TEST_P(HenyeyGreensteinTest, MeanCosineIsG) {
    const float g = GetParam();
    double sum = 0, sum2 = 0;
    for (int i = 0; i < kSamples; ++i) {
        Sampler sampler(std::hash<std::string>{}(Name(g) + "mean"), 0, 0, uint64_t(i));
        const double c =
            Dot(Vec3d(kTravel), Vec3d(SampleHenyeyGreenstein(kTravel, g, sampler.Get2D()).wi));
        sum += c;
        sum2 += c * c;
    }
    const double mean = sum / kSamples;
    const double se = std::sqrt((sum2 / kSamples - mean * mean) / kSamples);
    EXPECT_NEAR(mean, g, 4 * se) << Name(g);
}

// Int p dw = 1 by quadrature over the cosine (the density is uniform in azimuth).
TEST_P(HenyeyGreensteinTest, DensityIntegratesToOne) {
    const float g = GetParam();
    const double integral = testing::Integrate1D(
        [&](double c) { return 2 * kPi * HenyeyGreenstein(float(c), g); }, -1, 1, 2000);
    EXPECT_NEAR(integral, 1, 1e-5) << Name(g);
}

// The pdf returned is the density of the direction returned, a unit vector.
TEST_P(HenyeyGreensteinTest, PdfIsTheDensity) {
    const float g = GetParam();
    for (int i = 0; i < 10'000; ++i) {
        Sampler sampler(7, 0, 0, uint64_t(i));
        const PhaseSample s = SampleHenyeyGreenstein(kTravel, g, sampler.Get2D());
        EXPECT_NEAR(Length(s.wi), 1, 1e-6);
        EXPECT_EQ(s.pdf, HenyeyGreenstein(Dot(kTravel, s.wi), g));
        EXPECT_GT(s.pdf, 0);
    }
}

INSTANTIATE_TEST_SUITE_P(Asymmetries, HenyeyGreensteinTest, ::testing::ValuesIn(kGs),
                         [](const auto& info) {
                             return (info.param < 0 ? "Minus" : "Plus") +
                                    std::to_string(int(std::lround(std::abs(info.param) * 10)));
                         });

// Isotropic at g = 0; g near 0 samples the isotropic directions continuously (no division by g),
// and g near +-1 stays finite.
TEST(HenyeyGreenstein, NearZeroAndNearOneAsymmetry) {
    EXPECT_FLOAT_EQ(HenyeyGreenstein(0.3f, 0), float(1 / (4 * kPi)));
    for (int i = 0; i < 1000; ++i) {
        Sampler sampler(11, 0, 0, uint64_t(i));
        const Vec2 u = sampler.Get2D();
        const PhaseSample iso = SampleHenyeyGreenstein(kTravel, 0, u);
        EXPECT_NEAR(Dot(kTravel, iso.wi), 2 * u.x - 1, 2e-6);
        for (float g : {1e-7f, -1e-7f, 1e-4f, -1e-4f}) {
            const PhaseSample s = SampleHenyeyGreenstein(kTravel, g, u);
            // d cos / d g is at most 3/2 in magnitude at g = 0.
            EXPECT_NEAR(Dot(kTravel, s.wi), Dot(kTravel, iso.wi), 1.5 * std::abs(g) + 2e-6) << g;
        }
        for (float g : {0.999f, -0.999f}) {
            const PhaseSample s = SampleHenyeyGreenstein(kTravel, g, u);
            EXPECT_TRUE(IsFinite(s.wi) && std::isfinite(s.pdf) && s.pdf > 0) << g;
            EXPECT_NEAR(Length(s.wi), 1, 1e-6);
        }
    }
    // The extremes of u reach straight back and straight on.
    EXPECT_NEAR(Dot(kTravel, SampleHenyeyGreenstein(kTravel, 0.5f, {0, 0}).wi), -1, 1e-6);
    EXPECT_NEAR(Dot(kTravel, SampleHenyeyGreenstein(kTravel, 0.5f, {1, 0}).wi), 1, 1e-6);
}

}  // namespace
}  // namespace lf
