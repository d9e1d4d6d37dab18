#include "lf/core/sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

namespace lf {
namespace {

// Whether `points` (2^m of them, in [0, 1)^2) form a (0,m,2)-net in base 2: for every split
// m = a + b, each of the 2^a x 2^b elementary boxes holds exactly one point.
bool IsNet(const std::vector<Vec2>& points, int m) {
    for (int a = 0; a <= m; ++a) {
        const int b = m - a;
        std::vector<int> count(size_t(1) << m, 0);
        for (const Vec2& p : points) {
            const int ix = int(p.x * float(1 << a));
            const int iy = int(p.y * float(1 << b));
            if (++count[size_t(ix) << b | size_t(iy)] > 1) return false;
        }
    }
    return true;
}

TEST(Sobol, FirstPointsAreTheSobolSequence) {
    // Dimension 0 is van der Corput; dimension 1's matrix is Pascal's triangle mod 2.
    const double expect0[] = {0, 0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875};
    const double expect1[] = {0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
    for (uint32_t i = 0; i < 8; ++i) {
        EXPECT_EQ(SobolDimension0(i) * 0x1p-32, expect0[i]) << i;
        EXPECT_EQ(SobolDimension1(i) * 0x1p-32, expect1[i]) << i;
    }
}

TEST(Sobol, EveryAlignedBlockIsANetInTheFirstTwoDimensions) {
    for (int m = 0; m <= 12; ++m) {
        for (uint32_t block : {0u, 1u, 7u, 1000u}) {
            std::vector<Vec2> points;
            for (uint32_t i = 0; i < (1u << m); ++i) {
                const uint32_t index = (block << m) | i;
                points.push_back({float((SobolDimension0(index) >> 8) * 0x1p-24),
                                  float((SobolDimension1(index) >> 8) * 0x1p-24)});
            }
            EXPECT_TRUE(IsNet(points, m)) << "m " << m << " block " << block;
        }
    }
}

TEST(Sobol, NestedUniformScrambleMapsAlignedBlocksOntoAlignedBlocks) {
    for (uint32_t seed : {0u, 1u, 0xdeadbeefu}) {
        for (int m : {0, 3, 8}) {
            std::set<uint32_t> high;
            std::set<uint32_t> all;
            for (uint32_t i = 0; i < (1u << m); ++i) {
                const uint32_t x = NestedUniformScramble((5u << m) | i, seed);
                high.insert(m == 32 ? 0 : x >> m);
                all.insert(x);
            }
            EXPECT_EQ(high.size(), 1u) << "seed " << seed << " m " << m;
            EXPECT_EQ(all.size(), size_t(1) << m);
        }
    }
}

// What a path asks of the sampler: the first 2^m samples of one half (even or odd samples) of
// one pixel, for each of its first few Get2D calls (with a Get1D in between, as the path
// tracer interleaves them), all within the first Sampler::kSobolDraws draws.
std::vector<std::vector<Vec2>> PixelDimensions(uint64_t seed, int px, int py, int half, int m,
                                               int calls) {
    std::vector<std::vector<Vec2>> dims{size_t(calls)};
    for (uint64_t j = 0; j < (uint64_t(1) << m); ++j) {
        Sampler sampler(seed, px, py, 2 * j + uint64_t(half), SamplerType::kSobol);
        for (int c = 0; c < calls; ++c) {
            dims[size_t(c)].push_back(sampler.Get2D());
            sampler.Get1D();
        }
    }
    return dims;
}

TEST(SobolSampler, EachHalfsFirstPowerOfTwoSamplesAreNetsInEvery2DProjection) {
    for (int m = 0; m <= 10; ++m) {
        for (const auto& [px, py] : {std::pair{0, 0}, {17, 3}, {4095, 65535}}) {
            for (int half : {0, 1}) {
                const auto dims = PixelDimensions(42, px, py, half, m, 4);
                for (size_t c = 0; c < dims.size(); ++c) {
                    EXPECT_TRUE(IsNet(dims[c], m)) << "pixel " << px << "," << py << " half "
                                                   << half << " call " << c << " m " << m;
                }
            }
        }
    }
}

TEST(SobolSampler, DrawsPastTheSobolOnesAreTheIndependentSamplersNumbers) {
    static_assert(Sampler::kSobolDraws >= 8, "the nets test above checks 8 Sobol draws");
    for (uint64_t s : {0, 1, 7, 1000}) {
        Sampler sobol(3, 11, 12, s, SamplerType::kSobol);
        Sampler independent(3, 11, 12, s, SamplerType::kIndependent);
        for (uint64_t d = 0; d < Sampler::kSobolDraws; ++d) {
            sobol.Get1D();
            independent.Get1D();
        }
        const Vec2 a = sobol.Get2D(), b = independent.Get2D();
        EXPECT_EQ(a.x, b.x) << "sample " << s;
        EXPECT_EQ(a.y, b.y) << "sample " << s;
        EXPECT_EQ(sobol.Get1D(), independent.Get1D()) << "sample " << s;
    }
}

TEST(SobolSampler, TheTwoHalvesAreIndependentSequences) {
    // Sample 2j and 2j+1 of a pixel come from differently scrambled sequences: their values
    // are uncorrelated (within 4 standard errors over many pixels), not a stratified pair.
    const int n = 4096;
    double cross = 0;
    for (int i = 0; i < n; ++i) {
        const double even = Sampler(5, i % 64, i / 64, 0, SamplerType::kSobol).Get1D() - 0.5;
        const double odd = Sampler(5, i % 64, i / 64, 1, SamplerType::kSobol).Get1D() - 0.5;
        cross += even * odd;
    }
    EXPECT_LT(std::abs(cross / n * 12), 4 / std::sqrt(double(n)));
}

TEST(SobolSampler, Get1DIsStratifiedToo) {
    // 2^m samples of one half in a Get1D: one in each interval [k/2^m, (k+1)/2^m).
    const int m = 8;
    for (int call = 0; call < 4; ++call) {
        std::set<int> cells;
        for (uint64_t j = 0; j < (uint64_t(1) << m); ++j) {
            Sampler sampler(9, 3, 5, 2 * j, SamplerType::kSobol);
            for (int c = 0; c < call; ++c) sampler.Get2D();
            cells.insert(int(sampler.Get1D() * (1 << m)));
        }
        EXPECT_EQ(cells.size(), size_t(1) << m) << "call " << call;
    }
}

TEST(SobolSampler, PixelsAndDimensionsAreUncorrelated) {
    // Over 4096 pixels, sample 0's values of neighbouring pixels and of consecutive dimensions:
    // uniform means and correlations within 4 standard errors of 0 (1/sqrt(n) each).
    const int n = 4096;
    double sum = 0, sum_sq = 0, cross_pixel = 0, cross_dim = 0;
    for (int i = 0; i < n; ++i) {
        Sampler a(3, i % 64, i / 64, 0, SamplerType::kSobol);
        Sampler b(3, i % 64 + 1, i / 64, 0, SamplerType::kSobol);
        const double a0 = a.Get1D() - 0.5, a1 = a.Get1D() - 0.5, b0 = b.Get1D() - 0.5;
        sum += a0;
        sum_sq += a0 * a0;
        cross_pixel += a0 * b0;
        cross_dim += a0 * a1;
    }
    const double var = 1.0 / 12;
    EXPECT_LT(std::abs(sum / n), 4 * std::sqrt(var / n));
    EXPECT_NEAR(sum_sq / n, var, 4 * std::sqrt(1.0 / 180 / n));  // Var(u^2) for centred u
    EXPECT_LT(std::abs(cross_pixel / n / var), 4 / std::sqrt(double(n)));
    EXPECT_LT(std::abs(cross_dim / n / var), 4 / std::sqrt(double(n)));
}

TEST(SobolSampler, ValuesArePureFunctionsOfSeedPixelSampleAndDimension) {
    Sampler a(7, 10, 20, 12345, SamplerType::kSobol);
    Sampler b(7, 10, 20, 12345, SamplerType::kSobol);
    Sampler other_seed(8, 10, 20, 12345, SamplerType::kSobol);
    for (int i = 0; i < 16; ++i) {
        const Vec2 va = a.Get2D(), vb = b.Get2D(), vc = other_seed.Get2D();
        EXPECT_EQ(va.x, vb.x);
        EXPECT_EQ(va.y, vb.y);
        EXPECT_FALSE(va.x == vc.x && va.y == vc.y);
        EXPECT_GE(va.x, 0.0f);
        EXPECT_LT(va.x, 1.0f);
    }
}

}  // namespace
}  // namespace lf
