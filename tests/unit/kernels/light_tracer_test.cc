// Light tracing (lf/kernels/light_tracer.h): pbrt-v4's furnace spheres, agreement with the path
// tracer region by region, split invariance, and the frame-method factory.
#include "lf/kernels/light_tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "frame_render.h"
#include "frame_scenes.h"
#include "lf/core/scene_loader.h"
#include "render_path.h"

namespace lf {
namespace {

// The image mean of R, G, B averaged, over K independent batches of light paths, with its
// standard error from the spread of the batch means.
testing::MeanAndError BatchedFrameMean(const Scene& scene, const FrameRenderSettings& settings,
                                       int batches, uint64_t paths_per_batch) {
    const testing::FrameSetup s = testing::MakeFrameSetup(scene, "light", settings);
    std::vector<double> means;
    for (int b = 0; b < batches; ++b) {
        const uint64_t begin = uint64_t(b) * paths_per_batch;
        const Image image =
            testing::RenderFramePaths(*s.renderer, *s.camera, begin, begin + paths_per_batch).image;
        double sum = 0;
        for (const char* c : {"R", "G", "B"}) {
            for (float v : *image.FindChannel(c)) sum += v;
        }
        means.push_back(sum / (3.0 * image.width() * image.height()));
    }
    double mean = 0, var = 0;
    for (double m : means) mean += m / batches;
    for (double m : means) var += (m - mean) * (m - mean) / (batches - 1);
    return {mean, std::sqrt(var / batches)};
}

FrameRenderSettings Unlimited() {
    FrameRenderSettings settings;
    settings.max_depth = -1;
    settings.seed = 7;
    return settings;
}

// pbrt-v4's test: inside a sphere of albedo 0.5 lit by a point light of intensity pi at its
// centre the radiance is 1 everywhere.
TEST(LightTracer, PointLitFurnaceSphereIsOne) {
    const Scene scene = testing::PointLitFurnaceSphere(16);
    const testing::MeanAndError m = BatchedFrameMean(scene, Unlimited(), 32, 1 << 15);
    std::printf("[light] point-lit furnace sphere: %.5f +- %.5f (expected 1)\n", m.mean,
                m.standard_error);
    EXPECT_NEAR(m.mean, testing::kFurnaceSphereRadiance, 4.5 * m.standard_error);
    EXPECT_LT(m.standard_error, 0.01) << "too few paths for the test to mean anything";
}

// The same sphere emitting Le = 0.5 instead: L = 1, the emitter seen directly (the light
// vertex connected to the camera) plus every bounce.
TEST(LightTracer, EmissiveFurnaceSphereIsOne) {
    const Scene scene = testing::EmissiveFurnaceSphere(16);
    const testing::MeanAndError m = BatchedFrameMean(scene, Unlimited(), 32, 1 << 15);
    std::printf("[light] emissive furnace sphere: %.5f +- %.5f (expected 1)\n", m.mean,
                m.standard_error);
    EXPECT_NEAR(m.mean, testing::kFurnaceSphereRadiance, 4.5 * m.standard_error);
    EXPECT_LT(m.standard_error, 0.01);
}

// max_depth 0 leaves the emitter seen directly: Le = 0.5, with no noise at all but the
// estimator's (each pixel's value is Le for a box filter, up to the splat count).
TEST(LightTracer, DepthZeroIsTheEmitterSeenDirectly) {
    const Scene scene = testing::EmissiveFurnaceSphere(16);
    FrameRenderSettings settings = Unlimited();
    settings.max_depth = 0;
    const testing::MeanAndError m = BatchedFrameMean(scene, settings, 16, 1 << 14);
    EXPECT_NEAR(m.mean, 0.5, 4.5 * m.standard_error + 1e-6);
}

Scene LoadTestScene(const char* name, int size) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/" + name);
    EXPECT_TRUE(scene.ok()) << scene.status();
    scene->camera.width = scene->camera.height = size;
    return *std::move(scene);
}

// One work item and the same paths in sub-ranges (odd sizes, across chunk boundaries) give the
// same splat list, entry for entry, and the same counts.
TEST(LightTracer, AnySplitGivesTheSameSplats) {
    const Scene scene = LoadTestScene("materials.json", 24);
    const testing::FrameSetup s = testing::MakeFrameSetup(scene, "light", Unlimited());
    const int w = s.camera->width(), h = s.camera->height();
    constexpr uint64_t kPaths = 20000;
    SplatList whole(w, h);
    TileSums whole_sums(PixelRect{});
    s.renderer->Render({PixelRect{}, 0, 0, 0, kPaths}, whole_sums, whole);
    SplatList parts(w, h);
    TileSums part_sums(PixelRect{});
    for (const auto [begin, end] : {std::pair<uint64_t, uint64_t>{0, 1},
                                    {1, 1023},
                                    {1023, 5000},
                                    {5000, 5001},
                                    {5001, kPaths}}) {
        SplatList part(w, h);
        s.renderer->Render({PixelRect{}, 0, 0, begin, end}, part_sums, part);
        parts += part;
    }
    EXPECT_GT(whole.entries().size(), 100u);
    EXPECT_EQ(whole.entries(), parts.entries());
    EXPECT_EQ(whole_sums.stats.samples, kPaths);
    EXPECT_EQ(part_sums.stats.samples, kPaths);
    EXPECT_EQ(whole_sums.stats.rays, part_sums.stats.rays);
    EXPECT_EQ(whole_sums.stats.invalid_samples, part_sums.stats.invalid_samples);
}

TEST(LightTracer, CancelledRenderStopsEarly) {
    const Scene scene = LoadTestScene("cornell_box.json", 16);
    const testing::FrameSetup s = testing::MakeFrameSetup(scene, "light", Unlimited());
    std::atomic<bool> cancel{true};
    SplatList splats(16, 16);
    TileSums sums(PixelRect{});
    s.renderer->Render({PixelRect{}, 0, 0, 0, 1 << 20}, sums, splats, &cancel);
    EXPECT_EQ(sums.stats.samples, 0u);
    EXPECT_TRUE(splats.entries().empty());
}

TEST(FrameRendererFactory, BuildsLightAndRefusesWhatItCannot) {
    EXPECT_TRUE(IsFrameMethod("light"));
    EXPECT_TRUE(IsFrameMethod("bdpt"));
    EXPECT_TRUE(IsFrameMethod("ppm"));
    EXPECT_FALSE(IsFrameMethod("path"));
    EXPECT_FALSE(IsFrameMethod("whitted"));
    Scene scene = testing::PointLitFurnaceSphere(8);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const Camera camera(scene.camera, (*es)->origin());
    EXPECT_TRUE(MakeFrameRenderer("light", **es, camera, {}).ok());
    const auto path = MakeFrameRenderer("path", **es, camera, {});
    EXPECT_EQ(path.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(path.status().message().find("path"), std::string::npos);

    scene.camera.filter = {PixelFilter::Type::kGaussian, 2};
    const Camera gaussian(scene.camera, (*es)->origin());
    const auto refused = MakeFrameRenderer("light", **es, gaussian, {});
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(refused.status().message().find("light"), std::string::npos);
    EXPECT_NE(refused.status().message().find("gaussian"), std::string::npos);
}

}  // namespace
}  // namespace lf
