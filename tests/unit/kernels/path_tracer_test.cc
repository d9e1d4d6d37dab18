// The path tracer against analytic answers: furnaces at several albedos and scales, and a
// point light over a Lambertian plane.
#include "lf/kernels/path_tracer.h"

#include <gtest/gtest.h>

#include <numbers>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/local_executor.h"
#include "plane_render.h"
#include "render_path.h"
#include "splat_scenes.h"
#include "test_scenes.h"

namespace lf {
namespace {

// 5 standard errors: a correct renderer fails with probability below 1e-6 per check.
constexpr double kSigmas = 5.0;

RenderOutput Render(const Scene& scene, uint64_t spp, int max_depth = -1, uint64_t seed = 1) {
    return testing::RenderPath(scene, spp, max_depth, seed).out;
}

struct FurnaceCase {
    float rho;
    double half;
    double offset;
};

class Furnace : public ::testing::TestWithParam<FurnaceCase> {};

// A closed box emitting Le with albedo rho everywhere: L = Le / (1 - rho) at every point,
// the Neumann series summed to infinite depth (roulette only).
TEST_P(Furnace, RadianceIsEmissionOverOneMinusAlbedo) {
    const FurnaceCase c = GetParam();
    const float le = 0.5f;
    const Scene scene =
        testing::MakeFurnace(c.half, Vec3d(c.offset, c.offset, c.offset), c.rho, le, 16);
    const RenderOutput out = Render(scene, 64);
    const double expected = le / (1.0 - c.rho);
    EXPECT_EQ(out.stats.invalid_samples, 0u);
    for (const char* channel : {"R", "G", "B"}) {
        const testing::MeanAndError m = testing::ChannelMean(out.image, channel);
        if (c.rho == 0) {
            EXPECT_NEAR(m.mean, expected, 1e-6 * expected) << channel;
            continue;
        }
        // The check has power only if the noise is small next to a plausible bug (a lost bounce).
        EXPECT_LT(m.standard_error, 0.01 * expected) << channel;
        EXPECT_NEAR(m.mean, expected, kSigmas * m.standard_error) << channel;
    }
}

INSTANTIATE_TEST_SUITE_P(Albedos, Furnace,
                         ::testing::Values(FurnaceCase{0.0f, 1.0, 0.0}, FurnaceCase{0.5f, 1.0, 0.0},
                                           FurnaceCase{0.9f, 1.0, 0.0},
                                           // Scale extremes and far from the origin: leaks or
                                           // self-intersection would lose energy and show here.
                                           FurnaceCase{0.9f, 1e-4, 0.0},
                                           FurnaceCase{0.9f, 1e5, 0.0}, FurnaceCase{0.9f, 1.0, 1e5},
                                           FurnaceCase{0.5f, 1e3, 1e5}),
                         [](const auto& info) {
                             return "rho" + std::to_string(int(info.param.rho * 100)) + "_case" +
                                    std::to_string(info.index);
                         });

// pbrt-v4's integrator tests, as every method has them (splat_scenes.h): inside a sphere of
// albedo 0.5 lit by a point light of intensity pi at its centre, and inside the same sphere
// emitting 0.5, the radiance is 1 everywhere; under both light strategies (the BVH's sphere
// sampling from a point on the emitter itself lost light once).
TEST(Furnace, PbrtSpheresHaveMeanRadianceOne) {
    for (const LightStrategy strategy : {LightStrategy::kPower, LightStrategy::kBvh}) {
        for (const bool emissive : {false, true}) {
            const Scene scene =
                emissive ? testing::EmissiveFurnaceSphere(16) : testing::PointLitFurnaceSphere(16);
            const RenderOutput out =
                testing::RenderPath(scene, 256, -1, 1, SamplerType::kSobol, strategy).out;
            const testing::MeanAndError m = testing::ChannelMean(out.image, "G");
            EXPECT_LT(m.standard_error, 0.01);
            EXPECT_NEAR(m.mean, testing::kFurnaceSphereRadiance, kSigmas * m.standard_error)
                << (emissive ? "emissive" : "point light") << ", " << LightStrategyName(strategy);
        }
    }
}

TEST(Furnace, MaxDepthTruncatesTheNeumannSeries) {
    // With at most N bounces, L = Le (1 + rho + ... + rho^N).
    const float rho = 0.5f, le = 1.0f;
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), rho, le, 16);
    for (int depth : {0, 1, 3}) {
        const RenderOutput out = Render(scene, 64, depth);
        const double expected = le * (1 - std::pow(rho, depth + 1)) / (1 - rho);
        const testing::MeanAndError m = testing::ChannelMean(out.image, "G");
        EXPECT_NEAR(m.mean, expected, kSigmas * m.standard_error + 1e-6) << "depth " << depth;
    }
}

// A point light of intensity I at height h over a Lambertian plane of albedo rho:
// L(x) = rho/pi * I cos(theta) / r^2 with cos(theta) = h / r.
TEST(PointLight, LambertianPlaneMatchesInverseSquareLaw) {
    const Rgb rho(0.5f, 0.25f, 0.75f);
    Scene scene = testing::PlaneUnderCamera(rho);
    const Vec3d light(0.3, 1.0, -0.2);
    const Rgb intensity(10.0f, 5.0f, 2.0f);
    scene.point_lights.push_back({light, intensity});
    const uint64_t spp = 64;
    const RenderOutput out = Render(scene, spp, -1);
    const int compared = testing::ExpectPlaneMatches(scene, out.image, spp, [&](const Vec3d& x) {
        const double dist2 = LengthSquared(light - x);
        const double cos_theta = light.y / std::sqrt(dist2);
        return rho * intensity * float(cos_theta / dist2 / std::numbers::pi);
    });
    EXPECT_EQ(compared, testing::kPlaneImageSize * testing::kPlaneImageSize);
}

}  // namespace
}  // namespace lf

namespace lf {
namespace {

// The Cornell box moved 10^5 units from the origin renders the same image up to noise.
TEST(FarFromOrigin, TranslatedCornellBoxMatches) {
    absl::StatusOr<Scene> near = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    ASSERT_TRUE(near.ok()) << near.status();
    near->camera.width = near->camera.height = 32;
    Scene far = *near;
    const Vec3d shift(1e5, -1e5, 1e5);
    for (TriangleMesh& mesh : far.meshes) {
        for (Vec3d& p : mesh.positions) p += shift;
    }
    far.camera.position += shift;
    far.camera.look_at += shift;
    const RenderOutput a = Render(*near, 64), b = Render(far, 64);
    EXPECT_EQ(b.stats.invalid_samples, 0u);
    for (int c = 0; c < 3; ++c) {
        const char* names[3] = {"R", "G", "B"};
        const auto blocks_a = testing::BlockStatistics(a.image, names[c], 8),
                   blocks_b = testing::BlockStatistics(b.image, names[c], 8);
        for (size_t i = 0; i < blocks_a.size(); ++i) {
            const double sigma = std::sqrt(blocks_a[i].second + blocks_b[i].second);
            EXPECT_NEAR(blocks_a[i].first, blocks_b[i].first, kSigmas * sigma + 1e-6)
                << "block " << i << " channel " << c;
        }
    }
}

}  // namespace
}  // namespace lf
