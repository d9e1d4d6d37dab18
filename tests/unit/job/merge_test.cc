// Task results merged in any order give the bits of the whole render; bad or repeated results
// are refused without touching the image.
#include "lf/job/merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "lf/core/sampler.h"

namespace lf {
namespace {

// A made-up sample value, a pure function of (pixel, sample) like a real render's, spanning
// several orders of magnitude so float sums would depend on the order.
Rgb SampleValue(int x, int y, uint64_t s) {
    Sampler sampler(11, x, y, s);
    const float u = sampler.Get1D();
    return Rgb(std::exp(20 * u - 10), u, float(x + y) * 0.37f);
}

TileSums RenderFake(const PixelRect& rect, uint64_t begin, uint64_t end) {
    TileSums tile(rect);
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
        for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
            for (uint64_t s = begin; s < end; ++s) tile.at(x, y).Add(s, SampleValue(x, y, s));
        }
    }
    tile.stats.samples = uint64_t(rect.Area()) * (end - begin);
    return tile;
}

constexpr int kWidth = 37, kHeight = 21;
constexpr uint64_t kSpp = 7;

Image Reference() {
    Image image(kWidth, kHeight);
    image.SetTile(RenderFake({0, 0, kWidth, kHeight}, 0, kSpp));
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

}  // namespace
}  // namespace lf
