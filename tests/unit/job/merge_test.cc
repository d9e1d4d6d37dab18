// Task results merged in any order give the bits of the whole render; bad or repeated results
// are refused without touching the image.
#include "lf/job/merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "lf/core/aov.h"
#include "lf/core/sampler.h"

namespace lf {
namespace {

constexpr float kWidthForAovs = 37;

// A made-up sample value, a pure function of (pixel, sample) like a real render's, spanning
// several orders of magnitude so float sums would depend on the order.
Rgb SampleValue(int x, int y, uint64_t s) {
    Sampler sampler(11, x, y, s);
    const float u = sampler.Get1D();
    return Rgb(std::exp(20 * u - 10), u, float(x + y) * 0.37f);
}

// Made-up AOVs: every third sample misses, the others hit at depths over 12 orders of magnitude.
std::optional<FirstHit> AovValue(int x, int y, uint64_t s) {
    if (s % 3 == 2) return std::nullopt;
    Sampler sampler(12, x, y, s);
    const float u = sampler.Get1D();
    return FirstHit{Rgb(u, 0.5f, float(x) / kWidthForAovs), Vec3(u - 0.5f, -0.25f, 1),
                    std::exp(28 * u - 14)};
}

TileSums RenderFake(const PixelRect& rect, uint64_t begin, uint64_t end, uint32_t aovs = 0) {
    TileSums tile(rect, aovs);
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
        for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
            for (uint64_t s = begin; s < end; ++s) {
                tile.at(x, y).Add(s, SampleValue(x, y, s));
                if (aovs == 0) continue;
                if (const std::optional<FirstHit> hit = AovValue(x, y, s)) {
                    tile.aov_pixels[tile.Index(x, y)].Add(aovs, *hit);
                }
            }
        }
    }
    tile.stats.samples = uint64_t(rect.Area()) * (end - begin);
    return tile;
}

constexpr int kWidth = 37, kHeight = 21;
constexpr uint64_t kSpp = 7;

Image Reference(uint32_t aovs = 0) {
    Image image(kWidth, kHeight);
    image.SetTile(RenderFake({0, 0, kWidth, kHeight}, 0, kSpp, aovs));
    return image;
}

void ExpectSameBits(const Image& a, const Image& b) {
    ASSERT_EQ(a.channels().size(), b.channels().size());
    for (const auto& [name, data] : a.channels()) {
        const std::vector<float>* other = b.FindChannel(name);
        ASSERT_NE(other, nullptr) << name;
        EXPECT_EQ(0, std::memcmp(data.data(), other->data(), data.size() * sizeof(float))) << name;
    }
}

TEST(RenderMerger, AnyOrderGivesTheBitsOfTheWholeRender) {
    const Image reference = Reference();
    const std::vector<RenderTask> plan = *PlanRender({kWidth, kHeight, kSpp, 8, 3});
    for (unsigned seed : {1u, 2u, 3u}) {
        std::vector<RenderTask> order = plan;
        std::shuffle(order.begin(), order.end(), std::mt19937(seed));
        RenderMerger merger(kWidth, kHeight, plan);
        for (const RenderTask& t : order) {
            ASSERT_FALSE(merger.Complete());
            ASSERT_TRUE(merger.Add(t.index, RenderFake(t.rect, t.sample_begin, t.sample_end)).ok());
        }
        ASSERT_TRUE(merger.Complete());
        EXPECT_EQ(merger.stats().samples, uint64_t(kWidth * kHeight) * kSpp);
        ExpectSameBits(*merger.Snapshot(), reference);
    }
}

TEST(RenderMerger, SnapshotShowsWhatArrived) {
    const std::vector<RenderTask> plan = *PlanRender({kWidth, kHeight, kSpp, 8, 2});
    RenderMerger merger(kWidth, kHeight, plan);
    const Image empty = *merger.Snapshot();
    for (const char* ch : {"R", "G", "B", "A.R", "B.B", "spp"}) {
        ASSERT_NE(empty.FindChannel(ch), nullptr) << ch;
    }
    const RenderTask& first = plan[0];
    ASSERT_TRUE(merger.Add(0, RenderFake(first.rect, first.sample_begin, first.sample_end)).ok());
    const Image partial = *merger.Snapshot();
    const std::vector<float>& spp = *partial.FindChannel("spp");
    EXPECT_EQ(spp[0], float(first.sample_end - first.sample_begin));
    EXPECT_EQ(spp[size_t(kWidth) * (kHeight - 1)], 0.0f);
}

TEST(RenderMerger, RefusesRepeatedAndMismatchedResults) {
    const std::vector<RenderTask> plan = *PlanRender({kWidth, kHeight, kSpp, 8, 2});
    RenderMerger merger(kWidth, kHeight, plan);
    const RenderTask& t = plan[1];
    ASSERT_TRUE(merger.Add(1, RenderFake(t.rect, t.sample_begin, t.sample_end)).ok());
    const Image before = *merger.Snapshot();

    EXPECT_EQ(merger.Add(1, RenderFake(t.rect, t.sample_begin, t.sample_end)).code(),
              absl::StatusCode::kAlreadyExists);
    EXPECT_EQ(merger.Add(0, RenderFake(plan[2].rect, 0, 3)).code(),
              absl::StatusCode::kInvalidArgument);  // another tile
    EXPECT_EQ(merger.Add(0, RenderFake(plan[0].rect, 0, 1)).code(),
              absl::StatusCode::kInvalidArgument);  // too few samples
    EXPECT_EQ(merger.Add(int(plan.size()), RenderFake(t.rect, 0, 1)).code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(merger.tasks_done(), 1u);
    ExpectSameBits(*merger.Snapshot(), before);
}

TEST(RenderMerger, AovsMergedInAnyOrderGiveTheBitsOfTheWholeRender) {
    for (uint32_t aovs : {uint32_t(kAovAlbedo), uint32_t(kAovNormal | kAovDepth), kAllAovs}) {
        const Image reference = Reference(aovs);
        const std::vector<RenderTask> plan = *PlanRender({kWidth, kHeight, kSpp, 8, 3});
        std::vector<RenderTask> order = plan;
        std::shuffle(order.begin(), order.end(), std::mt19937(aovs));
        RenderMerger merger(kWidth, kHeight, plan, aovs);
        // A snapshot before any result already has the AOV channels, and only those asked for.
        const Image empty = *merger.Snapshot();
        EXPECT_EQ(empty.FindChannel("albedo.G") != nullptr, (aovs & kAovAlbedo) != 0);
        EXPECT_EQ(empty.FindChannel("normal.X") != nullptr, (aovs & kAovNormal) != 0);
        EXPECT_EQ(empty.FindChannel("depth.Z") != nullptr, (aovs & kAovDepth) != 0);
        for (const RenderTask& t : order) {
            ASSERT_TRUE(
                merger.Add(t.index, RenderFake(t.rect, t.sample_begin, t.sample_end, aovs)).ok());
        }
        ExpectSameBits(*merger.Snapshot(), reference);
    }
    // Depth averages the hits only: a pixel's depth.Z is the mean of its hits' depths.
    const Image image = Reference(kAovDepth);
    double sum = 0;
    int hits = 0;
    for (uint64_t s = 0; s < kSpp; ++s) {
        if (const std::optional<FirstHit> hit = AovValue(4, 3, s)) {
            sum += hit->depth;
            ++hits;
        }
    }
    EXPECT_FLOAT_EQ((*image.FindChannel("depth.Z"))[size_t(3 * kWidth + 4)], float(sum / hits));
}

TEST(RenderMerger, RefusesResultsWithOtherAovsThanTheJob) {
    const std::vector<RenderTask> plan = *PlanRender({kWidth, kHeight, kSpp, 8, 1});
    RenderMerger merger(kWidth, kHeight, plan, kAovDepth);
    const RenderTask& t = plan[0];
    for (uint32_t wrong : {0u, uint32_t(kAovAlbedo), kAllAovs}) {
        const absl::Status s =
            merger.Add(0, RenderFake(t.rect, t.sample_begin, t.sample_end, wrong));
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(s.message().find("the job's [depth]"), std::string_view::npos) << s;
    }
    EXPECT_EQ(merger.tasks_done(), 0u);
    EXPECT_TRUE(merger.Add(0, RenderFake(t.rect, t.sample_begin, t.sample_end, kAovDepth)).ok());
}

}  // namespace
}  // namespace lf
