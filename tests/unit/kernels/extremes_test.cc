// The path tracer where renderers usually break, each against an analytic expectation: a
// furnace of albedo 0.99 (long paths, bounded work), reflectance 1 with emission (no roulette
// can end a path), a tiny very bright emitter (fireflies territory), and sliver triangles seen
// at grazing angles. Albedo 0 and 0.5 furnaces are in path_tracer_test.cc, radiosity's furnaces
// (0.5 to 0.99) and its refusal of reflectance 1 in radiosity_solver_test.cc and
// radiosity_test.cc, 10^6 samples in one pixel in film_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"
#include "render_path.h"
#include "test_scenes.h"

namespace lf {
namespace {

// 5 standard errors: a correct renderer fails with probability below 1e-6 per check.
constexpr double kSigmas = 5.0;

using Rendered = testing::PathRender;

Rendered Render(const Scene& scene, uint64_t spp, int max_depth = -1) {
    return testing::RenderPath(scene, spp, max_depth, 5);
}

TriangleMesh Quad(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d, int material) {
    TriangleMesh m;
    m.material = material;
    m.is_quad = true;
    m.positions = {a, b, c, d};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

constexpr double kLampHeight = 1, kLampHalf = 0.005, kLampRadiance = 1e5;

// A 1 cm square emitter of radiance 1e5 at height 1, facing down onto a 20 x 20 floor of the
// given type; the camera looks straight down from height 0.5.
Scene TinyEmitterScene(Material::Type floor_type, float reflectance) {
    const double h = kLampHeight, a = kLampHalf;
    Scene scene;
    Material floor;
    floor.name = "floor";
    floor.type = floor_type;
    floor.reflectance = Rgb(reflectance);
    Material lamp;
    lamp.name = "lamp";
    lamp.reflectance = Rgb(0);
    lamp.emission = Rgb(float(kLampRadiance));
    scene.materials = {floor, lamp};
    scene.meshes.push_back(Quad({-10, 0, -10}, {-10, 0, 10}, {10, 0, 10}, {10, 0, -10}, 0));
    scene.meshes.push_back(Quad({-a, h, -a}, {a, h, -a}, {a, h, a}, {-a, h, a}, 1));  // faces -y
    scene.camera = testing::SquareCamera({0, 0.5, 0}, {0, 0, 0}, {0, 0, 1}, 60, 16);
    return scene;
}

// Albedo 0.99: L = Le / (1 - rho) = 100 Le, from paths of 1 / (1 - rho) = 100 bounces on
// average (the roulette keeps the throughput at 1, so the bounce count is geometric). Each
// bounce casts at most two rays (the continuation and one shadow ray) and at least one.
TEST(Extremes, FurnaceOfAlbedo099HasBoundedWork) {
    const float rho = 0.99f, le = 0.5f;
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), rho, le, 16);
    const Rendered r = Render(scene, 64);
    EXPECT_EQ(r.out.stats.invalid_samples, 0u);
    EXPECT_EQ(r.out.stats.truncated_paths, 0u);
    const double expected = le / (1.0 - rho);
    for (const char* channel : {"R", "G", "B"}) {
        const testing::MeanAndError m = testing::ChannelMean(r.out.image, channel);
        EXPECT_LT(m.standard_error, 0.02 * expected) << channel;  // power against a lost bounce
        EXPECT_NEAR(m.mean, expected, kSigmas * m.standard_error) << channel;
    }
    // Geometric bounce count: mean 1 / (1 - rho), standard deviation sqrt(rho) / (1 - rho).
    const double n = double(r.out.stats.samples);
    const double bounces = 1 / (1 - double(rho));
    const double margin = kSigmas * std::sqrt(double(rho)) / (1 - double(rho)) / std::sqrt(n);
    const double rays_per_sample = double(r.out.stats.rays) / n;
    EXPECT_GT(rays_per_sample, bounces - margin);
    EXPECT_LT(rays_per_sample, 1 + 2 * (bounces + margin));
}

// Reflectance 1 with emission has no finite solution (radiosity refuses it); the path tracer
// must still stop: every path reaches the hard depth cap, which is counted. Each path sees the
// emission once per vertex, so the radiance is about Le (kMaxPathDepth + 1), finite.
TEST(Extremes, ReflectanceOneWithEmissionStopsAtTheDepthCap) {
    const float le = 0.5f;
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 1.0f, le, 2);
    const Rendered r = Render(scene, 1);
    EXPECT_EQ(r.out.stats.invalid_samples, 0u);
    EXPECT_GT(r.out.stats.truncated_paths, 0u);
    EXPECT_LE(r.out.stats.truncated_paths, r.out.stats.samples);
    EXPECT_LE(r.out.stats.rays, r.out.stats.samples * (2 * uint64_t(kMaxPathDepth) + 3));
    for (float v : *r.out.image.FindChannel("R")) {
        EXPECT_TRUE(std::isfinite(v));
        EXPECT_LE(v, 1.01 * le * (kMaxPathDepth + 1));
    }
    // --max-depth bounds the work as well, and gives the truncated series: Le (N + 1).
    scene.camera.width = scene.camera.height = 8;
    const Rendered capped = Render(scene, 16, 10);
    EXPECT_EQ(capped.out.stats.truncated_paths, 0u);
    const testing::MeanAndError m = testing::ChannelMean(capped.out.image, "G");
    EXPECT_NEAR(m.mean, le * 11, kSigmas * m.standard_error);
}

// The tiny emitter over a Lambertian floor: the floor's
// radiance is rho / pi * E with E = ∫ Le cos θ_l cos θ / r^2 dA, here summed over 8 x 8 pieces
// of the emitter (error ~ (1 cm / 8)^2 relative) and averaged over 4 x 4 points of each pixel's
// footprint. The mean over the image must match within 5 standard errors (from each pixel's
// A/B halves) plus 1e-3 for the footprint quadrature.
TEST(Extremes, TinyBrightEmitterMatchesTheAnalyticIrradiance) {
    const double h = kLampHeight, a = kLampHalf, rho = 0.5, le = kLampRadiance;
    const Scene scene = TinyEmitterScene(Material::Type::kLambert, float(rho));
    const Rendered r = Render(scene, 64);
    EXPECT_EQ(r.out.stats.invalid_samples, 0u);

    const Camera camera(scene.camera, r.embree->origin());
    const Vec3d origin = r.embree->origin();
    constexpr int kPieces = 8, kFootprint = 4;
    auto radiance_at = [&](const Vec3d& p) {
        double e = 0;
        const double da = (2 * a / kPieces) * (2 * a / kPieces);
        for (int i = 0; i < kPieces; ++i) {
            for (int j = 0; j < kPieces; ++j) {
                const Vec3d q(-a + (i + 0.5) * 2 * a / kPieces, h,
                              -a + (j + 0.5) * 2 * a / kPieces);
                const Vec3d v = q - p;
                const double r2 = Dot(v, v);
                e += le * da * v.y * v.y / (r2 * r2);  // cos θ_l = cos θ = v.y / r
            }
        }
        return rho / std::numbers::pi * e;
    };
    const std::vector<float>& image = *r.out.image.FindChannel("R");
    const std::vector<float>& ha = *r.out.image.FindChannel("A.R");
    const std::vector<float>& hb = *r.out.image.FindChannel("B.R");
    double difference = 0, variance = 0, expected_sum = 0;
    for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 16; ++x) {
            double expected = 0;
            for (int i = 0; i < kFootprint; ++i) {
                for (int j = 0; j < kFootprint; ++j) {
                    const Ray ray =
                        camera.GenerateRay(x, y, (i + 0.5f) / kFootprint, (j + 0.5f) / kFootprint);
                    const Vec3d o = Vec3d(ray.o.x, ray.o.y, ray.o.z) + origin;
                    const Vec3d d(ray.d.x, ray.d.y, ray.d.z);
                    expected += radiance_at(o + d * (-o.y / d.y));
                }
            }
            expected /= kFootprint * kFootprint;
            const size_t k = size_t(y) * 16 + x;
            difference += image[k] - expected;
            variance += 0.25 * (double(ha[k]) - hb[k]) * (double(ha[k]) - hb[k]);
            expected_sum += expected;
        }
    }
    EXPECT_NEAR(difference, 0, kSigmas * std::sqrt(variance) + 1e-3 * expected_sum);
    std::printf("tiny emitter: image mean %.5f, analytic %.5f, standard error %.2g\n",
                (expected_sum + difference) / 256, expected_sum / 256, std::sqrt(variance) / 256);
}

// The same emitter seen in a mirror floor can only be found by camera rays that happen to hit
// its reflection, a quarter of a percent of each of the four middle pixels (about 2.5 hits in
// 1024 samples each): fireflies, flagged as high variance for every seed; the diffuse floor,
// where next-event estimation finds the emitter from every point, is not. The relMSE alone
// would not do: ((A - B) / 2)^2 / R^2 is at most 1 for non-negative halves, so four noisy
// pixels of 256 give at most 4 / 256 = 0.0156, above the limit for 5 seeds of 12 only; the
// error of the mean radiance is what the fireflies dominate.
TEST(Extremes, FirefliesAreFlaggedAsHighVariance) {
    const Scene mirror = TinyEmitterScene(Material::Type::kMirror, 0.95f);
    const Scene diffuse = TinyEmitterScene(Material::Type::kLambert, 0.5f);
    // Independent samples: the camera sees the lamp in the mirror only through the pixel
    // position, a 2D integral that Sobol points stratify, so each half of a middle pixel gets
    // its share of hits to within one and there is no firefly to flag (with seed 4 the A and B
    // halves agree in every pixel). Fireflies are what independent numbers make here.
    for (uint64_t seed : {1, 2, 3, 4, 5, 6}) {
        const VarianceAssessment m =
            AssessVariance(
                testing::RenderPath(mirror, 1024, -1, seed, SamplerType::kIndependent).out.image)
                .value();
        const VarianceAssessment d =
            AssessVariance(testing::RenderPath(diffuse, 64, -1, seed).out.image).value();
        EXPECT_TRUE(m.high) << "seed " << seed;
        EXPECT_FALSE(d.high) << "seed " << seed;
        std::printf(
            "seed %d: mirror floor relMSE %.4f, mean error %.3f; diffuse floor relMSE %.2g, "
            "mean error %.2g\n",
            int(seed), m.relmse, m.mean_error, d.relmse, d.mean_error);
    }
}

// A sliver (1 x 1e-7) inside a furnace, and the camera skimming a wall at a grazing angle: no
// NaN or infinite sample, every pixel finite and non-negative, and the wall pixels (the furnace
// radiance Le / (1 - rho) at every point) still match on average.
TEST(Extremes, SliversAndGrazingAnglesGiveNoNaN) {
    const float rho = 0.5f, le = 0.5f;
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), rho, le, 16);
    TriangleMesh sliver;
    sliver.material = 0;
    sliver.positions = {{-0.5, 0, 0.3}, {0.5, 0, 0.3}, {0.5, 1e-7, 0.3}};
    sliver.triangles = {{0, 1, 2}};
    scene.meshes.push_back(sliver);
    scene.camera.position = {0, -0.999, -0.9};  // 1 mm above the floor
    scene.camera.look_at = {0, -0.9995, 1};     // along it, nearly parallel
    scene.camera.fov_y_deg = 30;
    const Rendered r = Render(scene, 32);
    EXPECT_EQ(r.out.stats.invalid_samples, 0u);
    for (const char* channel : {"R", "G", "B", "A.R", "B.R"}) {
        for (float v : *r.out.image.FindChannel(channel)) {
            ASSERT_TRUE(std::isfinite(v)) << channel;
            ASSERT_GE(v, 0) << channel;
        }
    }
    const testing::MeanAndError m = testing::ChannelMean(r.out.image, "G");
    // The sliver covers far less than a pixel; everything else is wall at Le / (1 - rho).
    EXPECT_NEAR(m.mean, le / (1 - rho), kSigmas * m.standard_error + 1e-3);
}

}  // namespace
}  // namespace lf
