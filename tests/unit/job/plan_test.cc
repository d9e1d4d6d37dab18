// The planner covers every sample of every pixel exactly once, keeps a tile's passes together,
// and refuses plans that are empty or could overflow the exact sums.
#include "lf/job/plan.h"

#include <gtest/gtest.h>

#include <map>

namespace lf {
namespace {

TEST(PlanRender, EverySampleOfEveryPixelOnce) {
    for (auto [w, h, tile, passes, spp] : {std::tuple{64, 64, 16, 2, 8},
                                           {70, 33, 32, 3, 7},
                                           {5, 9, 192, 1, 1},
                                           {1, 1, 1, 5, 5},
                                           {300, 200, 1000, 1, 3}}) {
        absl::StatusOr<std::vector<RenderTask>> plan =
            PlanRender({w, h, uint64_t(spp), tile, passes});
        ASSERT_TRUE(plan.ok()) << plan.status();
        std::vector<uint64_t> samples(size_t(w) * h, 0);
        std::map<std::pair<int, int>, uint64_t> next_sample;  // per tile: passes in order
        for (size_t i = 0; i < plan->size(); ++i) {
            const RenderTask& t = (*plan)[i];
            EXPECT_EQ(t.index, int(i));
            EXPECT_LE(t.rect.width, tile);
            EXPECT_LT(t.sample_begin, t.sample_end);
            uint64_t& next = next_sample[{t.rect.y0, t.rect.x0}];
            EXPECT_EQ(next, t.sample_begin);
            next = t.sample_end;
            for (int y = t.rect.y0; y < t.rect.y0 + t.rect.height; ++y) {
                for (int x = t.rect.x0; x < t.rect.x0 + t.rect.width; ++x) {
                    samples[size_t(y) * w + x] += t.sample_end - t.sample_begin;
                }
            }
        }
        for (uint64_t n : samples) EXPECT_EQ(n, uint64_t(spp));
        EXPECT_EQ(plan->size(),
                  size_t((w + tile - 1) / tile) * size_t((h + tile - 1) / tile) * passes);
    }
}

TEST(PlanRender, PassesOfATileAreConsecutive) {
    const auto plan = PlanRender({40, 40, 10, 20, 4});
    ASSERT_TRUE(plan.ok());
    for (size_t i = 0; i < plan->size(); ++i) {
        EXPECT_EQ((*plan)[i].rect, (*plan)[i - i % 4].rect);
    }
}

TEST(PlanRender, RefusesEmptyOrOverflowingPlans) {
    for (const RenderPlanSettings& s :
         {RenderPlanSettings{0, 10, 4, 8, 1}, RenderPlanSettings{10, 10, 0, 8, 1},
          RenderPlanSettings{10, 10, kMaxSpp + 1, 8, 1}, RenderPlanSettings{10, 10, 4, 0, 1},
          RenderPlanSettings{10, 10, 4, 8, 5}, RenderPlanSettings{10, 10, 4, 8, 0}}) {
        absl::StatusOr<std::vector<RenderTask>> plan = PlanRender(s);
        EXPECT_EQ(plan.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_FALSE(plan.status().message().empty());
    }
}

}  // namespace
}  // namespace lf
