#include "lf/core/film.h"

#include <gtest/gtest.h>

#include <random>

namespace lf {
namespace {

TEST(ExactSum, OrderDoesNotMatter) {
    std::mt19937 rng(3);
    std::lognormal_distribution<float> dist(0.0f, 4.0f);  // spans many orders of magnitude
    std::vector<float> values(10000);
    for (float& v : values) v = dist(rng);
    ExactSum forward, backward, split_a, split_b;
    for (float v : values) forward.Add(v);
    for (auto it = values.rbegin(); it != values.rend(); ++it) backward.Add(*it);
    for (size_t i = 0; i < values.size(); ++i) (i % 3 ? split_a : split_b).Add(values[i]);
    split_a += split_b;
    EXPECT_EQ(forward, backward);
    EXPECT_EQ(forward, split_a);
}

// 10^6 samples in one pixel: the accumulated mean is accurate to 1e-6 relative (here far
// better: the only rounding is the final conversion and the 2^-50 quantum per sample).
TEST(ExactSum, MillionSamplesLoseNothing) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> dist(0.0f, 2.0f);
    ExactSum sum;
    long double reference = 0;
    float naive = 0;
    const int n = 1'000'000;
    for (int i = 0; i < n; ++i) {
        const float v = dist(rng) + 1e-3f;
        sum.Add(v);
        reference += v;
        naive += v;
    }
    const double rel = std::abs(sum.Value() - double(reference)) / double(reference);
    EXPECT_LT(rel, 1e-12);
    // The check is meaningful: a float accumulator fails it by orders of magnitude.
    EXPECT_GT(std::abs(double(naive) - double(reference)) / double(reference), 1e-6);
}

TEST(PixelSums, HalvesSplitByParityAndMeanIsExact) {
    PixelSums p;
    for (uint64_t s = 0; s < 10; ++s) p.Add(s, Rgb(float(s), 2 * float(s), 1.0f));
    EXPECT_EQ(p.count[0], 5u);
    EXPECT_EQ(p.count[1], 5u);
    EXPECT_FLOAT_EQ(p.Mean().r, 4.5f);
    EXPECT_FLOAT_EQ(p.HalfMean(0).r, 4.0f);  // 0 2 4 6 8
    EXPECT_FLOAT_EQ(p.HalfMean(1).g, 10.0f);  // 2*(1 3 5 7 9)/5
    EXPECT_FLOAT_EQ(p.Mean().b, 1.0f);
}

TEST(ExactSum, SmallAndLargeValuesKeepPrecision) {
    ExactSum s;
    s.Add(1e-9f);
    EXPECT_NEAR(s.Value(), 1e-9, 1e-15);
    ExactSum big;
    big.Add(1e12f);
    big.Add(1.0f);
    EXPECT_DOUBLE_EQ(big.Value(), double(1e12f) + 1.0);
}

}  // namespace
}  // namespace lf
