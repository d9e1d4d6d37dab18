// Filter importance sampling: the box filter keeps the film numbers bit for bit, the gaussian
// and Blackman-Harris offsets follow their filters (chi-square against the filter integrated
// numerically, variance against its closed form) and stay inside the support.
#include "lf/core/pixel_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "chi_square.h"
#include "lf/core/sampler.h"

namespace lf {
namespace {

constexpr int kSamples = 200000;

// The filters as scene.h defines them, unnormalised, on [-width/2, width/2].
double Gaussian(double width, double x) {
    const double sigma = width / 6;
    return std::exp(-x * x / (2 * sigma * sigma));
}

constexpr double kBh[4] = {0.35875, 0.48829, 0.14128, 0.01168};
// The textbook window a0 - a1 cos(2 pi n / N) + a2 cos(4 pi n / N) - a3 cos(6 pi n / N) with
// n / N = x / width + 1/2.
double BlackmanHarris(double width, double x) {
    const double t = 2 * std::numbers::pi * (x / width + 0.5);
    return kBh[0] - kBh[1] * std::cos(t) + kBh[2] * std::cos(2 * t) - kBh[3] * std::cos(3 * t);
}

double Density(const PixelFilter& f, double x) {
    return f.type == PixelFilter::Type::kGaussian ? Gaussian(f.width, x)
                                                  : BlackmanHarris(f.width, x);
}

// Simpson's rule with `n` (even) intervals.
double Integrate(const PixelFilter& f, double a, double b, int n = 64) {
    const double h = (b - a) / n;
    double sum = Density(f, a) + Density(f, b);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4 : 2) * Density(f, a + i * h);
    return sum * h / 3;
}

std::vector<double> Offsets(const PixelFilter& filter, uint64_t seed) {
    const FilterSampler sampler(filter);
    std::vector<double> x;
    for (int i = 0; i < kSamples; ++i) {
        Sampler s(seed, i, 0, 0);
        const Vec2 p = sampler.Sample(s.Get2D());
        x.push_back(p.x - 0.5);
        x.push_back(p.y - 0.5);
    }
    return x;
}

TEST(FilterSampler, BoxKeepsTheFilmNumbersBitForBit) {
    const FilterSampler box(PixelFilter{});
    for (int i = 0; i < 10000; ++i) {
        Sampler s(1, i, 2, 3);
        const Vec2 u = s.Get2D();
        const Vec2 p = box.Sample(u);
        EXPECT_EQ(std::memcmp(&u, &p, sizeof(u)), 0);
    }
}

class FilterSamplerTest : public ::testing::TestWithParam<PixelFilter> {};

TEST_P(FilterSamplerTest, OffsetsStayInsideTheSupport) {
    const PixelFilter f = GetParam();
    for (double x : Offsets(f, 1)) {
        ASSERT_GE(x, -f.width / 2 - 1e-6);
        ASSERT_LE(x, f.width / 2 + 1e-6);
    }
    const FilterSampler sampler(f);
    EXPECT_NEAR(sampler.Offset(0), -f.width / 2, 1e-12);
    EXPECT_NEAR(sampler.Offset(std::nextafter(1.0, 0.0)), f.width / 2, 1e-9);
    EXPECT_NEAR(sampler.Offset(0.5), 0, 1e-9);  // symmetric filters: the median is the centre
}

// Mitsuba-style chi-square: 64 bins over the support, expected counts from the filter
// integrated by Simpson's rule; bins expecting fewer than 5 samples are pooled.
TEST_P(FilterSamplerTest, OffsetsFollowTheFilterByChiSquare) {
    const PixelFilter f = GetParam();
    constexpr int kBins = 64;
    const double r = f.width / 2;
    std::vector<double> observed(kBins, 0), expected(kBins);
    const std::vector<double> x = Offsets(f, 2);
    for (double v : x) {
        observed[size_t(std::clamp(int((v + r) / f.width * kBins), 0, kBins - 1))] += 1;
    }
    const double total = Integrate(f, -r, r, 4096);
    for (int b = 0; b < kBins; ++b) {
        expected[size_t(b)] =
            Integrate(f, -r + f.width * b / kBins, -r + f.width * (b + 1) / kBins) / total *
            double(x.size());
    }
    double chi2 = 0, pooled_o = 0, pooled_e = 0;
    int dof = -1;
    for (int b = 0; b < kBins; ++b) {
        if (expected[size_t(b)] < 5) {
            pooled_o += observed[size_t(b)];
            pooled_e += expected[size_t(b)];
            continue;
        }
        const double d = observed[size_t(b)] - expected[size_t(b)];
        chi2 += d * d / expected[size_t(b)];
        ++dof;
    }
    if (pooled_e > 0) {
        chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        ++dof;
    }
    EXPECT_GT(testing::ChiSquarePValue(chi2, dof), 0.01 / 6) << "chi2 " << chi2 << " dof " << dof;
}

// The variance of the offsets against the filter's own, within 5 standard errors of the sample
// variance (from its fourth moment).
TEST_P(FilterSamplerTest, VarianceIsTheFiltersOwn) {
    const PixelFilter f = GetParam();
    const double w = f.width;
    double expected = 0;
    if (f.type == PixelFilter::Type::kGaussian) {
        // N(0, sigma^2) truncated at +-3 sigma.
        const double sigma = w / 6, a = 3;
        const double phi = std::exp(-a * a / 2) / std::sqrt(2 * std::numbers::pi);
        expected = sigma * sigma * (1 - 2 * a * phi / std::erf(a / std::numbers::sqrt2));
    } else {
        // Integral of x^2 cos(2 pi k x / W) over the support is W^3 (-1)^k / (2 pi^2 k^2), and
        // the window is a0 + a1 cos(2 pi x / W) + a2 cos(4 pi x / W) + a3 cos(6 pi x / W).
        double m2 = kBh[0] / 12;
        for (int k = 1; k < 4; ++k) {
            m2 += kBh[k] * (k % 2 ? -1 : 1) / (2 * std::numbers::pi * std::numbers::pi * k * k);
        }
        expected = w * w * m2 / kBh[0];
    }
    const std::vector<double> x = Offsets(f, 3);
    double m2 = 0, m4 = 0, mean = 0;
    for (double v : x) {
        mean += v;
        m2 += v * v;
        m4 += v * v * v * v;
    }
    const double n = double(x.size());
    mean /= n;
    m2 /= n;
    m4 /= n;
    const double error = std::sqrt((m4 - m2 * m2) / n);
    EXPECT_NEAR(m2, expected, 5 * error) << "expected variance " << expected;
    EXPECT_NEAR(mean, 0, 5 * std::sqrt(m2 / n));
}

INSTANTIATE_TEST_SUITE_P(Filters, FilterSamplerTest,
                         ::testing::Values(PixelFilter{PixelFilter::Type::kGaussian, 3},
                                           PixelFilter{PixelFilter::Type::kGaussian, 0.5},
                                           PixelFilter{PixelFilter::Type::kGaussian, 16},
                                           PixelFilter{PixelFilter::Type::kBlackmanHarris, 4},
                                           PixelFilter{PixelFilter::Type::kBlackmanHarris, 1.5},
                                           PixelFilter{PixelFilter::Type::kBlackmanHarris, 0.5}),
                         [](const ::testing::TestParamInfo<PixelFilter>& info) {
                             const std::string name =
                                 info.param.type == PixelFilter::Type::kGaussian ? "Gaussian"
                                                                                 : "BlackmanHarris";
                             return name + std::to_string(int(info.param.width * 10));
                         });

}  // namespace
}  // namespace lf
