// The file-backed tile store against the in-memory one: the same snapshot bits for a fixed plan
// and an adaptive one, zero sums before a tile is written, and a tile of the wrong size refused.
#include "lf/job/tile_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <random>

#include "lf/core/aov.h"
#include "lf/core/sampler.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/merge.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// A made-up sample, a pure function of (pixel, sample), over orders of magnitude so that the
// bits depend on the sums being exact.
TileSums RenderFake(const RenderTask& task, uint32_t aovs = 0) {
    TileSums tile(task.rect, aovs);
    for (int y = task.rect.y0; y < task.rect.y0 + task.rect.height; ++y) {
        for (int x = task.rect.x0; x < task.rect.x0 + task.rect.width; ++x) {
            for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) {
                Sampler sampler(5, x, y, s);
                const float u = sampler.Get1D();
                tile.at(x, y).Add(s, Rgb(std::exp(12 * u - 6), u * (x % 5 == 0 ? 3 : 0.1f), u));
                if (aovs != 0 && u > 0.2f) {
                    tile.aov_pixels[tile.Index(x, y)].Add(
                        aovs, {Rgb(u, 1 - u, 0.5f), Vec3(0, u, -1), std::exp(30 * u)});
                }
            }
        }
    }
    tile.stats.samples = uint64_t(task.rect.Area()) * (task.sample_end - task.sample_begin);
    return tile;
}

void ExpectSameBits(const Image& a, const Image& b) {
    ASSERT_EQ(a.channels().size(), b.channels().size());
    for (const auto& [name, data] : a.channels()) {
        const std::vector<float>* other = b.FindChannel(name);
        ASSERT_NE(other, nullptr) << name;
        ASSERT_EQ(data.size(), other->size()) << name;
        EXPECT_EQ(0, std::memcmp(data.data(), other->data(), data.size() * sizeof(float))) << name;
    }
}

class FileTileStoreTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_tiles_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    TileStoreFactory InFiles() const {
        return [dir = dir_.string()](std::vector<PixelRect> tiles, uint32_t aovs) {
            return MakeFileTileStore(dir, std::move(tiles), aovs);
        };
    }

    fs::path dir_;
};

TEST_F(FileTileStoreTest, FixedPlanSnapshotsHaveTheBitsOfTheMemoryStore) {
    constexpr int kWidth = 37, kHeight = 21;
    absl::StatusOr<std::vector<RenderTask>> plan = PlanRender({kWidth, kHeight, 6, 8, 3});
    ASSERT_TRUE(plan.ok()) << plan.status();
    RenderMerger memory(kWidth, kHeight, *plan);
    absl::StatusOr<std::unique_ptr<RenderMerger>> file =
        RenderMerger::Make(kWidth, kHeight, *plan, InFiles());
    ASSERT_TRUE(file.ok()) << file.status();
    std::vector<RenderTask> order = *plan;
    std::shuffle(order.begin(), order.end(), std::mt19937(3));
    for (size_t i = 0; i < order.size(); ++i) {
        const TileSums sums = RenderFake(order[i]);
        ASSERT_TRUE(memory.Add(order[i].index, sums).ok());
        ASSERT_TRUE((*file)->Add(order[i].index, sums).ok());
        if (i == order.size() / 2) ExpectSameBits(*(*file)->Snapshot(), *memory.Snapshot());
    }
    ASSERT_TRUE((*file)->Complete());
    ExpectSameBits(*(*file)->Snapshot(), *memory.Snapshot());
}

TEST_F(FileTileStoreTest, AovSnapshotsHaveTheBitsOfTheMemoryStore) {
    constexpr int kWidth = 19, kHeight = 13;
    for (uint32_t aovs : {uint32_t(kAovNormal), kAllAovs}) {
        absl::StatusOr<std::vector<RenderTask>> plan = PlanRender({kWidth, kHeight, 6, 8, 2});
        ASSERT_TRUE(plan.ok()) << plan.status();
        RenderMerger memory(kWidth, kHeight, *plan, aovs);
        absl::StatusOr<std::unique_ptr<RenderMerger>> file =
            RenderMerger::Make(kWidth, kHeight, *plan, InFiles(), aovs);
        ASSERT_TRUE(file.ok()) << file.status();
        ExpectSameBits(*(*file)->Snapshot(), *memory.Snapshot());
        for (const RenderTask& task : *plan) {
            const TileSums sums = RenderFake(task, aovs);
            ASSERT_TRUE(memory.Add(task.index, sums).ok());
            ASSERT_TRUE((*file)->Add(task.index, sums).ok());
        }
        const Image image = *(*file)->Snapshot();
        ASSERT_NE(image.FindChannel("normal.Y"), nullptr);
        ExpectSameBits(image, *memory.Snapshot());
    }
}

TEST_F(FileTileStoreTest, AdaptivePlanPlansAndMergesAsWithTheMemoryStore) {
    const AdaptiveSettings settings{.target_error = 0.05, .time_limit = 0, .max_spp = 256};
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> memory =
        AdaptiveTilePlan::Make(24, 16, 4, 8, settings, 200);
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> file =
        AdaptiveTilePlan::Make(24, 16, 4, 8, settings, 200, InFiles());
    ASSERT_TRUE(memory.ok() && file.ok());
    for (size_t t = 0; t < (*memory)->tasks().size(); ++t) {
        ASSERT_LT(t, (*file)->tasks().size());
        const RenderTask task = (*memory)->tasks()[t];
        const TileSums sums = RenderFake(task);
        ASSERT_TRUE((*memory)->Merge(int(t), sums).ok());
        ASSERT_TRUE((*file)->Merge(int(t), sums).ok());
    }
    ASSERT_TRUE((*file)->Complete());
    EXPECT_EQ((*file)->tasks().size(), (*memory)->tasks().size());
    EXPECT_GT((*file)->tasks().size(), (*file)->tile_count());  // some tiles took more passes
    ExpectSameBits(*(*file)->Snapshot(), *(*memory)->Snapshot());
    absl::StatusOr<AdaptiveReport> a = (*file)->Report(), b = (*memory)->Report();
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->estimated_error, b->estimated_error);
    EXPECT_EQ(a->max_spp, b->max_spp);
}

TEST_F(FileTileStoreTest, ReadsZeroSumsBeforeAPutAndThePutSumsAfter) {
    const PixelRect a{0, 0, 4, 3}, b{4, 0, 2, 3};
    absl::StatusOr<std::unique_ptr<TileStore>> store = MakeFileTileStore(dir_.string(), {a, b}, 0);
    ASSERT_TRUE(store.ok()) << store.status();
    absl::StatusOr<TileSums> before = (*store)->Get(1);
    ASSERT_TRUE(before.ok());
    EXPECT_EQ(before->rect, b);
    for (const PixelSums& p : before->pixels) EXPECT_EQ(p.Count(), 0u);
    const TileSums sums = RenderFake({0, b, 0, 6});
    ASSERT_TRUE((*store)->Put(1, sums).ok());
    absl::StatusOr<TileSums> after = (*store)->Get(1);
    ASSERT_TRUE(after.ok());
    for (size_t i = 0; i < sums.pixels.size(); ++i) {
        EXPECT_EQ(after->pixels[i].Count(), 6u);
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(after->pixels[i].sum[h][c], sums.pixels[i].sum[h][c]);
        }
    }
    // The file is unlinked once open: nothing is left behind, whatever happens to the process.
    EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(FileTileStoreTest, RefusesATileOfTheWrongSize) {
    const PixelRect a{0, 0, 4, 3};
    absl::StatusOr<std::unique_ptr<TileStore>> store = MakeFileTileStore(dir_.string(), {a}, 0);
    ASSERT_TRUE(store.ok()) << store.status();
    const absl::Status wrong = (*store)->Put(0, TileSums(PixelRect{0, 0, 4, 4}));
    EXPECT_EQ(wrong.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(wrong.message().find("tile 0 is 0,0 4x3"), std::string_view::npos) << wrong;
    EXPECT_EQ((*store)->Put(1, TileSums(a)).code(), absl::StatusCode::kInvalidArgument);
    absl::StatusOr<TileSums> kept = (*store)->Get(0);
    ASSERT_TRUE(kept.ok());
    EXPECT_EQ(kept->pixels.size(), 12u);
}

TEST_F(FileTileStoreTest, RefusesSumsWithOtherAovsThanTheStore) {
    const PixelRect a{0, 0, 4, 3};
    for (const TileStoreFactory& make : {InFiles(), TileStoreFactory(MakeMemoryTileStore)}) {
        absl::StatusOr<std::unique_ptr<TileStore>> store = make({a}, kAovAlbedo);
        ASSERT_TRUE(store.ok()) << store.status();
        EXPECT_EQ((*store)->aovs(), uint32_t(kAovAlbedo));
        const absl::Status plain = (*store)->Put(0, TileSums(a));
        EXPECT_EQ(plain.code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(plain.message().find("the store keeps [albedo]"), std::string_view::npos)
            << plain;
        EXPECT_EQ((*store)->Put(0, TileSums(a, kAllAovs)).code(),
                  absl::StatusCode::kInvalidArgument);
        EXPECT_TRUE((*store)->Put(0, TileSums(a, kAovAlbedo)).ok());
    }
}

TEST(MemoryTileStore, RefusesATileOfTheWrongSize) {
    absl::StatusOr<std::unique_ptr<TileStore>> store = MakeMemoryTileStore({{0, 0, 4, 3}}, 0);
    ASSERT_TRUE(store.ok());
    EXPECT_EQ((*store)->Put(0, TileSums(PixelRect{1, 0, 4, 3})).code(),
              absl::StatusCode::kInvalidArgument);
}

TEST_F(FileTileStoreTest, UnwritableFolderIsAnErrorNamingIt) {
    absl::StatusOr<std::unique_ptr<TileStore>> store =
        MakeFileTileStore((dir_ / "missing").string(), {{0, 0, 4, 3}}, 0);
    ASSERT_FALSE(store.ok());
    EXPECT_NE(store.status().message().find("missing"), std::string_view::npos) << store.status();
}

}  // namespace
}  // namespace lf
