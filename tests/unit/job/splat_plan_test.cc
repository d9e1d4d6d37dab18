// The frame planner covers every light path, camera sample and photon pass exactly once, and
// counts each task's light paths by half as the splats' normalisation needs.
#include "lf/job/splat_plan.h"

#include <gtest/gtest.h>

#include <map>
#include <tuple>

#include "lf/job/plan.h"

namespace lf {
namespace {

TEST(PlanSplatRender, LightPathsCoverEveryPathOnceInBoundedRanges) {
    for (auto [w, h, paths, per_task] : {std::tuple{64, 48, uint64_t(64 * 48 * 4), uint64_t(1000)},
                                         {7, 3, uint64_t(1), uint64_t(1 << 18)},
                                         {7, 3, uint64_t(21 * 5), uint64_t(21 * 5)},
                                         {3840, 2160, uint64_t(3840) * 2160, uint64_t(1) << 20}}) {
        SplatPlanSettings s;
        s.width = w;
        s.height = h;
        s.kind = SplatPlanKind::kLightPaths;
        s.light_paths = paths;
        s.max_paths_per_task = per_task;
        absl::StatusOr<std::vector<SplatTask>> plan = PlanSplatRender(s);
        ASSERT_TRUE(plan.ok()) << plan.status();
        uint64_t next = 0;
        std::array<uint64_t, 2> halves{};
        for (size_t i = 0; i < plan->size(); ++i) {
            const SplatTask& t = (*plan)[i];
            EXPECT_EQ(t.index, int(i));
            EXPECT_EQ(t.rect.Area(), 0);
            EXPECT_EQ(t.path_begin, next);  // consecutive: no gap, no overlap
            EXPECT_LT(t.path_begin, t.path_end);
            EXPECT_LE(t.path_end - t.path_begin, per_task);
            next = t.path_end;
            const std::array<uint64_t, 2> p = SplatPaths(SplatPlanKind::kLightPaths, t);
            EXPECT_EQ(p[0] + p[1], t.path_end - t.path_begin);
            halves[0] += p[0];
            halves[1] += p[1];
        }
        EXPECT_EQ(next, paths);
        EXPECT_EQ(halves[0], (paths + 1) / 2);  // even indices 0, 2, ...
        EXPECT_EQ(halves[1], paths / 2);
    }
}

TEST(PlanSplatRender, CameraAndLightIsTheTilePlanWithItsSamplesAsLightPaths) {
    SplatPlanSettings s;
    s.width = 70;
    s.height = 33;
    s.kind = SplatPlanKind::kCameraAndLight;
    s.spp = 7;
    s.tile = 32;
    s.passes = 3;
    const std::vector<SplatTask> plan = *PlanSplatRender(s);
    const std::vector<RenderTask> tiles = *PlanRender({70, 33, 7, 32, 3});
    ASSERT_EQ(plan.size(), tiles.size());
    std::array<uint64_t, 2> halves{};
    for (size_t i = 0; i < plan.size(); ++i) {
        EXPECT_EQ(plan[i].rect, tiles[i].rect);
        EXPECT_EQ(plan[i].sample_begin, tiles[i].sample_begin);
        EXPECT_EQ(plan[i].sample_end, tiles[i].sample_end);
        const std::array<uint64_t, 2> p = SplatPaths(SplatPlanKind::kCameraAndLight, plan[i]);
        halves[0] += p[0];
        halves[1] += p[1];
    }
    EXPECT_EQ(halves[0], uint64_t(70 * 33) * 4);  // samples 0, 2, 4, 6
    EXPECT_EQ(halves[1], uint64_t(70 * 33) * 3);
}

TEST(PlanSplatRender, PhotonPassesCoverEveryPassOfEveryPixelOnce) {
    SplatPlanSettings s;
    s.width = 50;
    s.height = 20;
    s.kind = SplatPlanKind::kPhotonPasses;
    s.spp = 10;  // passes
    s.max_paths_per_task = 4;
    s.tile = 16;
    const std::vector<SplatTask> plan = *PlanSplatRender(s);
    std::vector<uint64_t> passes(50 * 20, 0);
    std::map<std::pair<int, int>, uint64_t> next;
    for (const SplatTask& t : plan) {
        EXPECT_EQ(t.path_begin, t.sample_begin);
        EXPECT_EQ(t.path_end, t.sample_end);
        EXPECT_LE(t.path_end - t.path_begin, 4u);
        uint64_t& n = next[{t.rect.y0, t.rect.x0}];
        EXPECT_EQ(n, t.path_begin);
        n = t.path_end;
        for (int y = t.rect.y0; y < t.rect.y0 + t.rect.height; ++y) {
            for (int x = t.rect.x0; x < t.rect.x0 + t.rect.width; ++x) {
                passes[size_t(y * 50 + x)] += t.path_end - t.path_begin;
            }
        }
        EXPECT_EQ(SplatPaths(SplatPlanKind::kPhotonPasses, t), (std::array<uint64_t, 2>{0, 0}));
    }
    for (uint64_t p : passes) EXPECT_EQ(p, 10u);
}

TEST(PlanSplatRender, RefusesEmptyOrOversizedPlans) {
    SplatPlanSettings s;
    s.width = 10;
    s.height = 10;
    s.light_paths = 0;
    EXPECT_FALSE(PlanSplatRender(s).ok());  // no light paths
    s.light_paths = 100 * (kMaxSpp + 1);
    EXPECT_FALSE(PlanSplatRender(s).ok());  // beyond kMaxSpp per pixel
    s.light_paths = 1000;
    s.max_paths_per_task = 0;
    EXPECT_FALSE(PlanSplatRender(s).ok());
    s.max_paths_per_task = 1;
    s.light_paths = 100 * kMaxSpp;  // 1.7e9 tasks of one path: refused before being made
    absl::StatusOr<std::vector<SplatTask>> many = PlanSplatRender(s);
    EXPECT_FALSE(many.ok());
    EXPECT_NE(many.status().message().find("tasks"), std::string::npos) << many.status();
    s.width = 65536;
    s.height = 32768;
    s.light_paths = 1;
    EXPECT_FALSE(PlanSplatRender(s).ok());  // 2^31 pixels: pixel indices would wrap
    s.width = 10;
    s.height = 10;
    s.kind = SplatPlanKind::kPhotonPasses;
    s.spp = 0;
    EXPECT_FALSE(PlanSplatRender(s).ok());
}

}  // namespace
}  // namespace lf
