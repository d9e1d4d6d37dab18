// A splat list sums exactly: any order of adds gives the same entries; its storage is bounded by
// the adds it has seen, not by the frame; restricting to rectangles partitions it.
#include "lf/core/splat_list.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>

#include "lf/core/sampler.h"

namespace lf {
namespace {

struct Splat {
    int x, y, half;
    Rgb value;
};

// Values over 16 orders of magnitude, so float sums would depend on the order.
std::vector<Splat> MakeSplats(int width, int height, int n, uint64_t seed) {
    std::vector<Splat> splats;
    for (int i = 0; i < n; ++i) {
        Sampler s(seed, 0, 0, uint64_t(i));
        const Vec2 p = s.Get2D();
        const float u = s.Get1D();
        splats.push_back({int(p.x * float(width)), int(p.y * float(height)), i & 1,
                          Rgb(std::exp(36 * u - 18), u, -u)});
    }
    return splats;
}

TEST(SplatList, AnyOrderOfAddsGivesTheSameEntries) {
    const std::vector<Splat> splats = MakeSplats(13, 7, 20000, 1);
    SplatList reference(13, 7);
    for (const Splat& s : splats) reference.Add(s.x, s.y, s.half, s.value);
    for (unsigned seed : {1u, 2u, 3u}) {
        std::vector<Splat> order = splats;
        std::shuffle(order.begin(), order.end(), std::mt19937(seed));
        // Split into three lists added together, as tasks' lists are.
        SplatList parts[3] = {SplatList(13, 7), SplatList(13, 7), SplatList(13, 7)};
        for (size_t i = 0; i < order.size(); ++i) {
            parts[i % 3].Add(order[i].x, order[i].y, order[i].half, order[i].value);
        }
        SplatList sum(13, 7);
        for (int k : {2, 0, 1}) sum += parts[k];
        EXPECT_EQ(sum.entries(), reference.entries()) << "order " << seed;
    }
}

TEST(SplatList, EntriesAreSortedDistinctAndSumTheirAdds) {
    SplatList list(4, 3);
    list.Add(3, 2, 1, Rgb(1, 2, 3));
    list.Add(0, 0, 0, Rgb(0.5f, 0, 0));
    list.Add(3, 2, 1, Rgb(1, 2, 3));
    list.Add(3, 2, 0, Rgb(4, 0, 0));
    list.Add(1, 1, 0, Rgb(1, 1, 1));
    list.Add(1, 1, 0, Rgb(-1, -1, -1));  // cancels exactly: the entry goes
    const std::vector<SplatEntry>& e = list.entries();
    ASSERT_EQ(e.size(), 3u);
    EXPECT_EQ(e[0].pixel, 0u);
    EXPECT_EQ(e[1].pixel, 11u);
    EXPECT_EQ(e[1].half, 0);
    EXPECT_EQ(e[2].pixel, 11u);
    EXPECT_EQ(e[2].half, 1);
    EXPECT_EQ(e[2].rgb[1].Value(), 4.0);
    EXPECT_EQ(e[0].rgb[0].Value(), 0.5);
}

// Storage after n adds: at most max(4096, 1.5 min(n, 2 x pixels)) entries (splat_list.h).
TEST(SplatList, StorageIsBoundedByTheAddsNotTheFrame) {
    // A 4K frame and few adds: a few hundred kilobytes, not the 796 MB of a dense layer.
    SplatList sparse(3840, 2160);
    for (const Splat& s : MakeSplats(3840, 2160, 3000, 2)) sparse.Add(s.x, s.y, s.half, s.value);
    EXPECT_LE(sparse.MemoryBytes(), 4096 * sizeof(SplatEntry));
    // Many adds on a small frame: bounded by its distinct (pixel, half) pairs at every step.
    for (auto [width, height, n] : {std::tuple{64, 64, 200000}, {300, 200, 150000}}) {
        SplatList list(width, height);
        size_t i = 0;
        for (const Splat& s : MakeSplats(width, height, n, 3)) {
            list.Add(s.x, s.y, s.half, s.value);
            ++i;
            const size_t distinct_bound = std::min(i, size_t(2 * width * height));
            ASSERT_LE(list.MemoryBytes(),
                      std::max<size_t>(4096, distinct_bound + distinct_bound / 2 + 1) *
                          sizeof(SplatEntry))
                << width << "x" << height << " after " << i << " adds";
        }
        EXPECT_LE(list.entries().size(), size_t(2 * width * height));
    }
    EXPECT_EQ(sizeof(SplatEntry), 64u);  // the figure the docs use
}

TEST(SplatList, RestrictionsToTilesPartitionTheList) {
    SplatList list(50, 30);
    for (const Splat& s : MakeSplats(50, 30, 5000, 4)) list.Add(s.x, s.y, s.half, s.value);
    SplatList joined(50, 30);
    size_t entries = 0;
    for (int y = 0; y < 30; y += 16) {
        for (int x = 0; x < 50; x += 16) {
            const PixelRect rect{x, y, std::min(16, 50 - x), std::min(16, 30 - y)};
            SplatList part = list.Restrict(rect);
            for (const SplatEntry& e : part.raw_entries()) {
                const int px = int(e.pixel % 50), py = int(e.pixel / 50);
                EXPECT_TRUE(px >= rect.x0 && px < rect.x0 + rect.width && py >= rect.y0 &&
                            py < rect.y0 + rect.height);
            }
            entries += part.raw_entries().size();
            joined += part;
        }
    }
    EXPECT_EQ(entries, list.entries().size());
    EXPECT_EQ(joined.entries(), list.entries());
}

TEST(SplatList, AddToPutsEachHalfInItsPixel) {
    SplatList list(8, 8);
    list.Add(5, 6, 1, Rgb(2, 3, 4));
    list.Add(4, 4, 0, Rgb(1, 0, 0));
    list.Add(0, 0, 0, Rgb(9, 9, 9));  // outside the tile: Restrict leaves it out
    TileSums tile({4, 4, 4, 4});
    list.Restrict(tile.rect).AddTo(tile);
    EXPECT_EQ(tile.at(5, 6).sum[1][2].Value(), 4.0);
    EXPECT_EQ(tile.at(5, 6).sum[0][2].Value(), 0.0);
    EXPECT_EQ(tile.at(4, 4).sum[0][0].Value(), 1.0);
    EXPECT_EQ(tile.at(5, 6).Count(), 0u);
}

}  // namespace
}  // namespace lf
