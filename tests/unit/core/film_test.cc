#include "lf/core/film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "lf/core/aov.h"

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
    EXPECT_FLOAT_EQ(p.HalfMean(0).r, 4.0f);   // 0 2 4 6 8
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

// AOV means: albedo and normal over every sample (misses count as 0), depth over the hits only,
// +inf for a pixel no sample hit.
TEST(AovSums, MeansOverSamplesAndDepthOverHits) {
    AovSums a;
    a.Add(kAllAovs, FirstHit{Rgb(0.5f, 0.25f, 1), Vec3(0, 1, 0), 2});
    a.Add(kAllAovs, FirstHit{Rgb(0.25f, 0.25f, 0), Vec3(0, 0, -1), 4});
    // Two more samples missed: 4 samples in the pixel.
    EXPECT_EQ(a.depth_hits, 2u);
    const Rgb albedo = a.Albedo(4);
    EXPECT_FLOAT_EQ(albedo.r, 0.1875f);
    EXPECT_FLOAT_EQ(albedo.g, 0.125f);
    EXPECT_FLOAT_EQ(albedo.b, 0.25f);
    const Vec3 n = a.Normal(4);
    EXPECT_FLOAT_EQ(n.y, 0.25f);
    EXPECT_FLOAT_EQ(n.z, -0.25f);
    EXPECT_FLOAT_EQ(a.Depth(), 3.0f);
    EXPECT_EQ(AovSums().Depth(), std::numeric_limits<float>::infinity());
    EXPECT_EQ(AovSums().Albedo(0).r, 0.0f);
    // Only the requested AOVs are summed.
    AovSums depth_only;
    depth_only.Add(kAovDepth, FirstHit{Rgb(1), Vec3(1, 0, 0), 5});
    EXPECT_EQ(depth_only.albedo[0], ExactSum());
    EXPECT_EQ(depth_only.normal[0], ExactSum());
    EXPECT_FLOAT_EQ(depth_only.Depth(), 5.0f);
}

// Depths beyond 2^50 clamp there, so kMaxSpp (2^24) samples of the largest depth still fit in the
// 127 bits: doubling one clamped sample 24 times gives 2^74, positive and exact.
TEST(AovSums, LargestDepthsOverTheMostSamplesDoNotOverflow) {
    AovSums a;
    a.Add(kAovDepth, FirstHit{Rgb(), Vec3(), 3e38f});
    for (int i = 0; i < 24; ++i) a += a;
    EXPECT_EQ(a.depth_hits, 1u << 24);
    EXPECT_EQ(a.depth.Value(), std::ldexp(1.0, 74));
    EXPECT_EQ(a.Depth(), float(std::ldexp(1.0, 50)));
}

}  // namespace
}  // namespace lf
