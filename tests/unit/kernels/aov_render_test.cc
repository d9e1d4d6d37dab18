// First-hit AOVs and the sample clamp through the tile renderer: a plane gives its albedo, normal
// and per-pixel distance; misses give 0 and an infinite depth; asking for AOVs changes no bit of
// the image, with the path tracer or a radiosity solution, which both see the same first hits;
// a clamp caps every sample (fireflies go, the mean drops) and a clamp of 0 is no clamp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "lf/core/aov.h"
#include "lf/core/camera.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiosity.h"
#include "lf/local/local_executor.h"
#include "plane_render.h"
#include "test_scenes.h"

namespace lf {
namespace {

struct Prepared {
    Scene scene;
    std::unique_ptr<EmbreeScene> embree;
    std::unique_ptr<Camera> camera;
    std::unique_ptr<PathTracer> tracer;
};

std::unique_ptr<Prepared> Prepare(Scene scene) {
    auto p = std::make_unique<Prepared>();
    p->scene = std::move(scene);
    p->embree = EmbreeScene::Build(p->scene).value();
    p->camera = std::make_unique<Camera>(p->scene.camera, p->embree->origin());
    p->tracer = std::make_unique<PathTracer>(*p->embree, -1);
    return p;
}

Image Render(const Camera& camera, const RadianceEstimator& estimator, uint64_t spp, uint32_t aovs,
             double clamp = 0) {
    RenderSettings settings;
    settings.spp = spp;
    settings.tile = 8;
    settings.aovs = aovs;
    settings.clamp = clamp;
    return RenderImage(camera, estimator, settings).value().image;
}

bool SameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The distance from the camera at height 3 to the plane y = 0 along the ray through film point
// (fx, fy) of PlaneUnderCamera's view.
double PlaneDepth(const Camera& camera, double fx, double fy) {
    const Ray ray = camera.GenerateRay(0, 0, float(fx), float(fy));
    return 3 / std::abs(double(ray.d.y));
}

TEST(AovRender, PlaneGivesItsAlbedoNormalAndDistance) {
    const Rgb rho(0.2f, 0.5f, 0.7f);
    Scene scene = testing::PlaneUnderCamera(rho);
    scene.point_lights.push_back({Vec3d(0, 2, 0), Rgb(1.0f)});
    const auto p = Prepare(scene);
    const Image image = Render(*p->camera, *p->tracer, 8, kAllAovs);
    const int n = testing::kPlaneImageSize;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const size_t i = size_t(y) * n + x;
            for (int c = 0; c < 3; ++c) {
                ASSERT_FLOAT_EQ((*image.FindChannel(kAovAlbedoChannels[c]))[i], rho[c]);
                ASSERT_NEAR((*image.FindChannel(kAovNormalChannels[c]))[i], c == 1 ? 1 : 0, 1e-6);
            }
            // The mean distance over the pixel's samples lies between the extremes of the
            // distance over the pixel (it is smallest at the image centre, largest at a corner).
            double lo = 1e300, hi = 0;
            for (double fy = 0; fy <= 1; fy += 0.125) {
                for (double fx = 0; fx <= 1; fx += 0.125) {
                    const double d = PlaneDepth(*p->camera, x + fx, y + fy);
                    lo = std::min(lo, d);
                    hi = std::max(hi, d);
                }
            }
            const float depth = (*image.FindChannel(kAovDepthChannel))[i];
            ASSERT_GE(depth, lo * (1 - 1e-6)) << x << "," << y;
            ASSERT_LE(depth, hi * (1 + 1e-6)) << x << "," << y;
        }
    }
}

// A mirror ball in the middle of an empty view: its pixels have albedo 1 (perfect specular, as
// OIDN asks) and unit normals facing the camera; a corner pixel no sample hits has albedo and
// normal 0 and an infinite depth; an edge pixel averages its misses in as 0.
TEST(AovRender, MissesAreZeroWithInfiniteDepthAndMirrorsHaveAlbedoOne) {
    Scene scene;
    Material mirror;
    mirror.type = Material::Type::kMirror;
    mirror.reflectance = Rgb(0.3f);
    scene.materials.push_back(mirror);
    scene.spheres.push_back({"ball", 0, Vec3d(0, 0, 0), 1});
    scene.camera = testing::SquareCamera({0, 0, -4}, {0, 0, 0}, {0, 1, 0}, 40, 16);
    const auto p = Prepare(scene);
    const Image image = Render(*p->camera, *p->tracer, 4, kAllAovs);
    const auto at = [&](const char* channel, int x, int y) {
        return (*image.FindChannel(channel))[size_t(y) * 16 + x];
    };
    EXPECT_EQ(at("albedo.R", 8, 8), 1.0f);
    EXPECT_NEAR(at("normal.Z", 8, 8), -1, 0.02);  // towards the camera at -z
    EXPECT_NEAR(at("depth.Z", 8, 8), 3, 0.02);
    EXPECT_EQ(at("albedo.G", 0, 0), 0.0f);
    EXPECT_EQ(at("normal.X", 0, 0), 0.0f);
    EXPECT_EQ(at("depth.Z", 0, 0), std::numeric_limits<float>::infinity());
    // Somewhere on the silhouette some samples hit and some missed.
    int partial = 0;
    for (int x = 0; x < 16; ++x) {
        const float a = at("albedo.B", x, 8);
        if (a > 0 && a < 1) {
            ++partial;
            EXPECT_TRUE(std::isfinite(at("depth.Z", x, 8)));
        }
    }
    EXPECT_GT(partial, 0);
}

// A furnace box seen from inside: the image's channels have the same bits
// with and without AOVs, and the AOVs are the same for the path tracer and a radiosity solution
// of the same scene (the first hit is a property of the scene, not of the method).
TEST(AovRender, AovsChangeNoBitOfTheImageWithEitherMethod) {
    const auto p = Prepare(testing::MakeFurnace(1.0, Vec3d(), 0.7f, 1.0f, 12));
    RadiosityOptions options;
    options.patches = 200;
    const std::unique_ptr<RadiosityRenderer> radiosity =
        PrepareRadiosity(*p->embree, options).value();
    const Image path_plain = Render(*p->camera, *p->tracer, 4, 0);
    const Image path_aovs = Render(*p->camera, *p->tracer, 4, kAllAovs);
    const Image radiosity_plain = Render(*p->camera, *radiosity, 4, 0);
    const Image radiosity_aovs = Render(*p->camera, *radiosity, 4, kAllAovs);
    for (const auto& [name, data] : path_plain.channels()) {
        EXPECT_TRUE(SameBits(data, *path_aovs.FindChannel(name))) << name;
        EXPECT_TRUE(SameBits(*radiosity_plain.FindChannel(name), *radiosity_aovs.FindChannel(name)))
            << name;
    }
    EXPECT_EQ(path_aovs.channels().size(), path_plain.channels().size() + 7);
    for (const char* name : {"albedo.R", "normal.X", "normal.Y", "normal.Z", "depth.Z"}) {
        EXPECT_TRUE(SameBits(*path_aovs.FindChannel(name), *radiosity_aovs.FindChannel(name)))
            << name;
    }
}

// A small, very bright light over a floor beside a mirror ball: camera rays that see the light,
// and floor paths that reach it through the mirror (only BSDF sampling finds them), are
// fireflies far above the floor's direct light.
Scene FireflyScene() {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    Material mirror;
    mirror.type = Material::Type::kMirror;
    mirror.reflectance = Rgb(1.0f);
    scene.materials.push_back(mirror);
    Material light;
    light.reflectance = Rgb(0.0f);
    light.emission = Rgb(500.0f, 400.0f, 200.0f);
    scene.materials.push_back(light);
    scene.spheres.push_back({"mirror", 1, Vec3d(0.5, 0.5, 0.3), 0.5});
    scene.spheres.push_back({"light", 2, Vec3d(-0.6, 1.0, -0.4), 0.15});
    scene.camera.width = scene.camera.height = 48;
    return scene;
}

// At one sample a pixel, each pixel is one sample: with the clamp none exceeds it, those below it
// keep their bits, those above keep their hue at the clamp; the mean drops (the bias).
TEST(ClampRender, CapsEverySampleKeepingItsHueAndLowersTheMean) {
    const auto p = Prepare(FireflyScene());
    constexpr double kClamp = 20;
    const Image plain = Render(*p->camera, *p->tracer, 1, 0);
    const Image clamped = Render(*p->camera, *p->tracer, 1, 0, kClamp);
    int above = 0;
    for (size_t i = 0; i < plain.FindChannel("R")->size(); ++i) {
        const Rgb a = plain.Pixel(int(i % 48), int(i / 48));
        const Rgb b = clamped.Pixel(int(i % 48), int(i / 48));
        if (a.MaxComponent() <= kClamp) {
            ASSERT_EQ(std::memcmp(&a, &b, sizeof(a)), 0) << i;
            continue;
        }
        ++above;
        EXPECT_NEAR(b.MaxComponent(), kClamp, kClamp * 1e-6);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c] / kClamp, a[c] / a.MaxComponent(), 1e-6);
    }
    EXPECT_GT(above, 0) << "the scene has no fireflies to clamp";
    EXPECT_LT(testing::ChannelMean(clamped, "R").mean, testing::ChannelMean(plain, "R").mean);
}

TEST(ClampRender, ZeroIsOffAndKeepsEveryBit) {
    const auto p = Prepare(FireflyScene());
    const Image plain = Render(*p->camera, *p->tracer, 4, 0);
    const Image zero = Render(*p->camera, *p->tracer, 4, 0, 0.0);
    for (const auto& [name, data] : plain.channels()) {
        EXPECT_TRUE(SameBits(data, *zero.FindChannel(name))) << name;
    }
}

}  // namespace
}  // namespace lf
