// Frame-pass results (camera tiles + splat lists) merged in any order, retried, or interrupted by
// a failing store give the bits of one process adding everything at once, normalised by the
// light paths per pixel-equivalent.
#include "lf/job/splat_merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "lf/core/sampler.h"
#include "lf/job/merge.h"

namespace lf {
namespace {

constexpr int kWidth = 37, kHeight = 21, kTile = 8;

// A made-up light path's splats: a pure function of the path's index, like a real kernel's, up
// to three anywhere on the frame with values over 16 orders of magnitude.
void FakeLightPath(uint64_t path, int half, SplatList& out) {
    Sampler s(21, 0, 0, path);
    const int n = int(s.Get1D() * 4);
    for (int k = 0; k < n; ++k) {
        const Vec2 p = s.Get2D();
        const float u = s.Get1D();
        out.Add(int(p.x * kWidth), int(p.y * kHeight), half, Rgb(std::exp(36 * u - 18), u, 1));
    }
}

// A made-up camera sample (BDPT's strategies with t >= 2), a pure function of (pixel, sample).
Rgb FakeCamera(int x, int y, uint64_t sample) {
    Sampler s(22, x, y, sample);
    const float u = s.Get1D();
    return Rgb(std::exp(20 * u - 10), u, float(x + y) * 0.37f);
}

struct Result {
    TileSums camera{PixelRect{}};
    SplatList splats{kWidth, kHeight};
};

// What a worker returns for `task`: light paths [path_begin, path_end) splat (half = the path's
// parity); camera samples of the rect add to the tile, each with its own light subpath (index
// (pixel, sample), half = the sample's parity) that splats anywhere.
Result RunFake(const SplatTask& task) {
    Result r;
    r.camera = TileSums(task.rect);
    for (uint64_t i = task.path_begin; i < task.path_end; ++i)
        FakeLightPath(i, int(i & 1), r.splats);
    for (int y = task.rect.y0; y < task.rect.y0 + task.rect.height; ++y) {
        for (int x = task.rect.x0; x < task.rect.x0 + task.rect.width; ++x) {
            for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) {
                r.camera.at(x, y).Add(s, FakeCamera(x, y, s));
                FakeLightPath((uint64_t(y * kWidth + x) << 32) + s, int(s & 1), r.splats);
            }
        }
    }
    r.camera.stats.samples = uint64_t(task.rect.Area()) * (task.sample_end - task.sample_begin) +
                             (task.path_end - task.path_begin);
    return r;
}

// One process adding every task's samples into one frame-sized tile and one list: what local
// mode does, with the same composition.
Image OneProcess(SplatPlanKind kind, const std::vector<SplatTask>& plan) {
    const PixelRect frame{0, 0, kWidth, kHeight};
    TileSums camera(frame), splat_sums(frame);
    SplatList splats(kWidth, kHeight);
    SplatNormalization norm;
    norm.frame_pixels = kWidth * kHeight;
    for (const SplatTask& t : plan) {
        Result r = RunFake(t);
        if (t.rect.Area() != 0) {
            for (int y = t.rect.y0; y < t.rect.y0 + t.rect.height; ++y) {
                for (int x = t.rect.x0; x < t.rect.x0 + t.rect.width; ++x) {
                    camera.at(x, y) += r.camera.at(x, y);
                }
            }
        }
        splats += r.splats;
        const std::array<uint64_t, 2> p = SplatPaths(kind, t);
        norm.paths[0] += p[0];
        norm.paths[1] += p[1];
    }
    splats.Coalesce();
    splats.AddTo(splat_sums);
    Image image = EmptyRenderImage(kWidth, kHeight);
    SetSplatTile(image, camera, splat_sums, norm);
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

SplatPlanSettings Settings(SplatPlanKind kind) {
    SplatPlanSettings s;
    s.width = kWidth;
    s.height = kHeight;
    s.kind = kind;
    s.tile = kTile;
    s.light_paths = uint64_t(kWidth * kHeight) * 3;
    s.max_paths_per_task = 100;  // 24 tasks, the last one short
    s.spp = 5;
    s.passes = 2;
    return s;
}

TEST(SplatMerger, AnyOrderGivesTheBitsOfOneProcess) {
    for (SplatPlanKind kind : {SplatPlanKind::kLightPaths, SplatPlanKind::kCameraAndLight}) {
        const std::vector<SplatTask> plan = *PlanSplatRender(Settings(kind));
        const Image reference = OneProcess(kind, plan);
        for (unsigned seed : {1u, 2u, 3u}) {
            std::vector<SplatTask> order = plan;
            std::shuffle(order.begin(), order.end(), std::mt19937(seed));
            std::unique_ptr<SplatMerger> merger =
                *SplatMerger::Make(kWidth, kHeight, kTile, kind, plan);
            for (const SplatTask& t : order) {
                ASSERT_FALSE(merger->Complete());
                Result r = RunFake(t);
                ASSERT_TRUE(merger->Add(t.index, r.camera, r.splats).ok());
            }
            EXPECT_TRUE(merger->Complete());
            ExpectSameBits(*merger->Snapshot(), reference);
        }
    }
}

TEST(SplatMerger, ARetriedTaskIsNotCountedTwice) {
    const std::vector<SplatTask> plan = *PlanSplatRender(Settings(SplatPlanKind::kCameraAndLight));
    const Image reference = OneProcess(SplatPlanKind::kCameraAndLight, plan);
    std::unique_ptr<SplatMerger> merger =
        *SplatMerger::Make(kWidth, kHeight, kTile, SplatPlanKind::kCameraAndLight, plan);
    for (const SplatTask& t : plan) {
        Result r = RunFake(t);
        ASSERT_TRUE(merger->Add(t.index, r.camera, r.splats).ok());
        // A second worker's copy of the same task (a retry after a lost lease) changes nothing.
        Result again = RunFake(t);
        EXPECT_EQ(merger->Add(t.index, again.camera, again.splats).code(),
                  absl::StatusCode::kAlreadyExists);
    }
    EXPECT_EQ(merger->tasks_done(), plan.size());
    ExpectSameBits(*merger->Snapshot(), reference);
}

// A memory store whose Puts fail while `*fail` is set.
class FlakyStore : public TileStore {
  public:
    FlakyStore(std::vector<PixelRect> tiles, std::shared_ptr<int> budget)
        : TileStore(tiles, 0), inner_(*MakeMemoryTileStore(tiles, 0)), budget_(std::move(budget)) {}
    absl::StatusOr<TileSums> Get(int tile) const override { return inner_->Get(tile); }
    absl::Status Put(int tile, const TileSums& sums) override {
        if (*budget_ == 0) return absl::UnavailableError("disk full");
        if (*budget_ > 0) --*budget_;
        return inner_->Put(tile, sums);
    }

  private:
    std::unique_ptr<TileStore> inner_;
    std::shared_ptr<int> budget_;  // Puts left before failing; -1: never fails
};

TEST(SplatMerger, AStoreFailureMidTaskThenARetryAddsEachTileOnce) {
    const SplatPlanKind kind = SplatPlanKind::kLightPaths;
    const std::vector<SplatTask> plan = *PlanSplatRender(Settings(kind));
    const Image reference = OneProcess(kind, plan);
    auto budget = std::make_shared<int>(-1);
    std::unique_ptr<SplatMerger> merger = *SplatMerger::Make(
        kWidth, kHeight, kTile, kind, plan,
        [&](std::vector<PixelRect> tiles, uint32_t) -> absl::StatusOr<std::unique_ptr<TileStore>> {
            return std::make_unique<FlakyStore>(std::move(tiles), budget);
        });
    for (const SplatTask& t : plan) {
        // Each task's splats span several tiles: let a few land, then fail the rest.
        *budget = 3;
        Result r = RunFake(t);
        EXPECT_EQ(merger->Add(t.index, r.camera, r.splats).code(), absl::StatusCode::kUnavailable);
        *budget = -1;
        Result retry = RunFake(t);
        ASSERT_TRUE(merger->Add(t.index, retry.camera, retry.splats).ok());
    }
    ExpectSameBits(*merger->Snapshot(), reference);
}

// Path i splats (1, 2, 0.5) onto pixel i mod P. With an odd P = 777 and tasks of P paths, task
// k gives pixel j one path of parity k + j, so after any even number of tasks every pixel has as
// many splats per half as each half has paths per pixel: each half and their mean are exactly
// (1, 2, 0.5), mid-render (divided by the paths merged so far) as at the end.
TEST(SplatMerger, SplatsAreDividedByTheLightPathsPerPixel) {
    SplatPlanSettings s = Settings(SplatPlanKind::kLightPaths);
    s.light_paths = 4 * kWidth * kHeight;
    s.max_paths_per_task = kWidth * kHeight;
    const std::vector<SplatTask> plan = *PlanSplatRender(s);
    ASSERT_EQ(plan.size(), 4u);
    std::unique_ptr<SplatMerger> merger =
        *SplatMerger::Make(kWidth, kHeight, kTile, SplatPlanKind::kLightPaths, plan);
    for (int k : {3, 0, 2, 1}) {
        const SplatTask& t = plan[size_t(k)];
        SplatList splats(kWidth, kHeight);
        for (uint64_t i = t.path_begin; i < t.path_end; ++i) {
            const int pixel = int(i % uint64_t(kWidth * kHeight));
            splats.Add(pixel % kWidth, pixel / kWidth, int(i & 1), Rgb(1, 2, 0.5f));
        }
        ASSERT_TRUE(merger->Add(t.index, TileSums(PixelRect{}), splats).ok());
        if (merger->tasks_done() % 2 != 0) continue;
        EXPECT_EQ(merger->normalization().paths[0], merger->tasks_done() / 2 * kWidth * kHeight);
        const Image image = *merger->Snapshot();
        for (int y = 0; y < kHeight; ++y) {
            for (int x = 0; x < kWidth; ++x) {
                for (const char* prefix : {"", "A.", "B."}) {
                    const Rgb v = image.Pixel(x, y, prefix);
                    ASSERT_EQ(v[0], 1.0f)
                        << prefix << x << "," << y << " after " << merger->tasks_done() << " tasks";
                    ASSERT_EQ(v[1], 2.0f);
                    ASSERT_EQ(v[2], 0.5f);
                }
            }
        }
    }
}

TEST(SplatMerger, RefusesResultsThatAreNotTheTasks) {
    const std::vector<SplatTask> light = *PlanSplatRender(Settings(SplatPlanKind::kLightPaths));
    std::unique_ptr<SplatMerger> merger =
        *SplatMerger::Make(kWidth, kHeight, kTile, SplatPlanKind::kLightPaths, light);
    SplatList other_frame(kWidth + 1, kHeight);
    EXPECT_EQ(merger->Add(0, TileSums(PixelRect{}), other_frame).code(),
              absl::StatusCode::kInvalidArgument);
    SplatList splats(kWidth, kHeight);
    EXPECT_EQ(merger->Add(0, TileSums(PixelRect{0, 0, kTile, kTile}), splats).code(),
              absl::StatusCode::kInvalidArgument);  // a camera tile from a light-path task
    EXPECT_EQ(merger->Add(int(light.size()), TileSums(PixelRect{}), splats).code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(merger->tasks_done(), 0u);

    const std::vector<SplatTask> bdpt = *PlanSplatRender(Settings(SplatPlanKind::kCameraAndLight));
    merger = *SplatMerger::Make(kWidth, kHeight, kTile, SplatPlanKind::kCameraAndLight, bdpt);
    Result r = RunFake(bdpt[0]);
    r.camera.at(0, 0).count[0] += 1;  // a pixel with one sample too many
    EXPECT_EQ(merger->Add(0, r.camera, r.splats).code(), absl::StatusCode::kInvalidArgument);

    SplatPlanSettings ppm = Settings(SplatPlanKind::kPhotonPasses);
    ppm.max_paths_per_task = 2;
    const std::vector<SplatTask> passes = *PlanSplatRender(ppm);
    merger = *SplatMerger::Make(kWidth, kHeight, kTile, SplatPlanKind::kPhotonPasses, passes);
    Result p = RunFake(passes[0]);
    p.splats.Add(1, 1, 0, Rgb(1));
    EXPECT_EQ(merger->Add(0, p.camera, p.splats).code(), absl::StatusCode::kInvalidArgument);

    // Camera rectangles off the merger's tile grid cannot be merged into one store tile.
    std::vector<SplatTask> off_grid = bdpt;
    off_grid[0].rect.x0 += 1;
    EXPECT_FALSE(
        SplatMerger::Make(kWidth, kHeight, kTile, SplatPlanKind::kCameraAndLight, off_grid).ok());
}

}  // namespace
}  // namespace lf
