// `plan`'s prediction of an adaptive render (PredictAdaptiveRender) against the render itself,
// and the pass rule it replays against NextSampleCount's own sequence.
#include "lf/local/render_prediction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"

namespace lf {
namespace {

// Error exactly 0.4 n^-1/2: the replay takes NextSampleCount's passes, 16 -> 128 (x8 cap) ->
// ceil(128 (0.0354 / 0.01)^2 1.1) ...; the pilot's points lie on the same law.
TEST(PredictTileSamples, FollowsThePassRule) {
    const auto error = [](double n) { return 0.4 / std::sqrt(n); };
    const TilePilot tile{256, 8, 32, error(8), error(32)};
    EXPECT_NEAR(ConvergenceRate(tile), 0.5, 1e-12);
    uint64_t n = 16;
    while (error(double(n)) > 0.01 && n < 65536)
        n = NextSampleCount(n, error(double(n)), 0.01, 65536);
    EXPECT_EQ(PredictTileSamples(tile, 0.5, 16, 0.01, 65536), n);
    EXPECT_EQ(PredictTileSamples(tile, 0.5, 16, 0.01, 1000), 1000u);  // capped by max_spp
    EXPECT_EQ(PredictTileSamples(tile, 0.5, 16, 0.5, 65536), 16u);    // the first pass suffices
}

// A tile whose first stage saw no noise (all its samples black: the light it reaches is rare)
// but whose second did: its error at n2 was measured at 0.2, and error does not rise with
// samples, so no count up to n2 meets a target of 0.01. The log-linear model between the
// stages divided by e1 = 0 and stopped the replay at the first pass (NaN, or 0 below n1).
TEST(PredictTileSamples, FirstStageWithoutNoiseDoesNotEndTheTile) {
    const TilePilot tile{256, 8, 32, 0.0, 0.2};
    for (const uint64_t first : {4u, 16u, 32u}) {
        EXPECT_GT(PredictTileSamples(tile, ConvergenceRate(tile), first, 0.01, 65536), 32u)
            << "first pass " << first;
    }
}

// A small render of the glossy room, its prediction first: within 2x of the samples it took.
// Fixed seeds, so the same numbers every run.
TEST(PredictAdaptiveRender, IsWithinTwiceTheRendersSamples) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/glossy_room.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene->camera.width = scene->camera.height = 32;
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    ASSERT_TRUE(embree.ok()) << embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    const PathTracer tracer(**embree, -1);
    RenderSettings settings;
    settings.spp = 16;
    settings.seed = 3;
    settings.tile = 16;
    settings.threads = 2;
    const AdaptiveSettings adaptive{.target_error = 0.1};
    absl::StatusOr<RenderPrediction> predicted =
        PredictAdaptiveRender(camera, tracer, settings, adaptive, 8);
    ASSERT_TRUE(predicted.ok()) << predicted.status();
    absl::StatusOr<RenderOutput> render = RenderImageAdaptive(camera, tracer, settings, adaptive);
    ASSERT_TRUE(render.ok()) << render.status();
    double samples = 0;
    for (const AdaptiveReport::Tile& t : render->adaptive.per_tile) {
        samples += double(t.spp) * t.rect.Area();
    }
    const double mean = samples / (32.0 * 32.0);
    std::printf("predicted %.0f spp (%.0f at rate 1/2), the render took %.0f\n",
                predicted->mean_spp, predicted->high_mean_spp, mean);
    EXPECT_GE(predicted->mean_spp, mean / 2);
    EXPECT_LE(predicted->mean_spp, mean * 2);
    EXPECT_GE(predicted->high_mean_spp, predicted->mean_spp);
}

}  // namespace
}  // namespace lf

namespace lf {
namespace {

// The method comparison's arithmetic: error 0.2 at 4 spp and 0.1 at 16 falls as spp^-1/2, so a
// target of 0.05 takes 64 spp, 16 s at the second stage's 4 spp/s.
TEST(PredictMethodCost, FollowsThePowerLawThroughTheStages) {
    const MethodCost c = PredictMethodCost({4, 1.0, 0.2}, {16, 4.0, 0.1}, 0.05, 0.5, 1).value();
    EXPECT_NEAR(c.rate, 0.5, 1e-12);
    EXPECT_NEAR(c.spp, 64, 1e-9);
    EXPECT_NEAR(c.seconds, 16, 1e-9);
    // Measured 2 (the second stage lucky): clamped to 1, so (0.025 / 0.01)^1 x 16 spp.
    const MethodCost fast = PredictMethodCost({4, 1, 0.4}, {16, 4, 0.025}, 0.01, 0.5, 1).value();
    EXPECT_NEAR(fast.rate, 1, 1e-12);
    EXPECT_NEAR(fast.spp, 40, 1e-9);
    // Photon mapping's rate alpha / 2 = 1/3: the target 4x below takes 4^3 = 64x the passes.
    const MethodCost ppm =
        PredictMethodCost({4, 1, 0.2}, {16, 4, 0.1}, 0.025, 1.0 / 3, 1.0 / 3).value();
    EXPECT_NEAR(ppm.spp, 16 * 64, 1e-6);
    // Met already: the second stage's cost; noiseless: the first's.
    EXPECT_EQ(PredictMethodCost({4, 1, 0.2}, {16, 4, 0.1}, 0.5, 0.5, 1).value().spp, 16);
    EXPECT_EQ(PredictMethodCost({4, 1, 0}, {16, 4, 0}, 0.5, 0.5, 1).value().seconds, 1);
}

TEST(PredictMethodCost, RefusesStagesOutOfOrderAndTargetsBelowZero) {
    EXPECT_FALSE(PredictMethodCost({16, 1, 0.2}, {4, 4, 0.1}, 0.05, 0.5, 1).ok());
    EXPECT_FALSE(PredictMethodCost({0, 1, 0.2}, {4, 4, 0.1}, 0.05, 0.5, 1).ok());
    EXPECT_FALSE(PredictMethodCost({4, 1, 0.2}, {16, 4, 0.1}, 0, 0.5, 1).ok());
    EXPECT_FALSE(PredictMethodCost({4, 1, 0.2}, {16, 4, 0.1}, 0.05, 1, 0.5).ok());
}

}  // namespace
}  // namespace lf
