// The illuminance AOV (lux on the side of the first hit the camera sees): a plane of albedo 0.5
// under a point light of I candela at height h reads I cos^3(theta) / h^2 (I / h^2 below the
// light) with the radiosity solution and with the path tracer, and that times Beer's law with
// the volumetric path tracer in an absorbing medium; asking for it changes no bit of the image.
// Radiosity reads it where the reflectance is 0 too: a black or pure-red plane, a lamp panel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "lf/core/aov.h"
#include "lf/core/camera.h"
#include "lf/core/photometry.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/vol_path_tracer.h"
#include "lf/local/local_executor.h"
#include "plane_render.h"
#include "test_scenes.h"

namespace lf {
namespace {

constexpr double kCandela = 1000, kHeight = 2;

// An odd size: the middle pixel lies right under the light.
constexpr int kSize = 17;

// PlaneUnderCamera's view (camera at height 3, 60 degrees) of a 4 x 4 plane, albedo 0.5, lit by
// a white point light of kCandela candela (kCandela / 683 W/sr a channel, luminance Y = 1 per
// W/sr) kHeight above its centre; the image spans up to 41 degrees off the light's axis.
Scene LitPlane() {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    scene.camera.width = scene.camera.height = kSize;
    const double s = 2;
    scene.meshes[0].positions = {{-s, 0, -s}, {-s, 0, s}, {s, 0, s}, {s, 0, -s}};
    scene.point_lights.push_back({Vec3d(0, kHeight, 0), Rgb(float(kCandela / kLumensPerWatt))});
    return scene;
}

// I cos^3(theta) / h^2 at plane point p, times exp(-sigma_a d) over the distance d to the
// light in a medium absorbing sigma_a.
double ExpectedLux(const Vec3d& p, double sigma_a) {
    const double d = std::sqrt(p.x * p.x + p.z * p.z + kHeight * kHeight);
    const double cos_theta = kHeight / d;
    return kCandela * cos_theta * cos_theta * cos_theta / (kHeight * kHeight) *
           std::exp(-sigma_a * d);
}

// The lux of pixel (x, y) averaged over its footprint (box filter), and the spread over it: the
// standard deviation of one sample's position, the only randomness of a point light's estimate.
struct PixelLux {
    double mean = 0, sd = 0;
};
PixelLux ExpectedPixel(const Camera& camera, int x, int y, double sigma_a = 0) {
    constexpr int kGrid = 16;
    double sum = 0, sum2 = 0;
    for (int j = 0; j < kGrid; ++j) {
        for (int i = 0; i < kGrid; ++i) {
            const Ray ray = camera.GenerateRay(x, y, (i + 0.5f) / kGrid, (j + 0.5f) / kGrid);
            const Vec3d o(ray.o), d(ray.d);
            const double e = ExpectedLux(o - d * (o.y / d.y), sigma_a);
            sum += e;
            sum2 += e * e;
        }
    }
    const double n = kGrid * kGrid, mean = sum / n;
    return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean))};
}

// LitPlane cut into three strips along x: grey (albedo 0.5), black (0, under the light) and pure
// red (0.9, 0, 0). The light arriving is the same on all three.
Scene LitPlaneOfThreeAlbedos() {
    Scene scene = LitPlane();
    scene.materials.resize(3);
    scene.materials[1].reflectance = Rgb(0);
    scene.materials[2].reflectance = Rgb(0.9f, 0, 0);
    const TriangleMesh plane = scene.meshes[0];
    scene.meshes.clear();
    const double s = 2, edges[4] = {-s, -s / 3, s / 3, s};
    for (int k = 0; k < 3; ++k) {
        TriangleMesh strip = plane;
        strip.material = k;
        strip.positions = {
            {edges[k], 0, -s}, {edges[k], 0, s}, {edges[k + 1], 0, s}, {edges[k + 1], 0, -s}};
        scene.meshes.push_back(strip);
    }
    return scene;
}

// LitPlane with the camera, the plane and the light in a medium absorbing sigma_a (no
// scattering: Beer's law exactly), which the volumetric path tracer renders.
Scene LitPlaneInAbsorber(float sigma_a) {
    Scene scene = LitPlane();
    Medium absorber;
    absorber.sigma_a = Rgb(sigma_a);
    scene.media.push_back(absorber);
    scene.camera_medium = 0;
    return scene;
}

struct Prepared {
    explicit Prepared(Scene s = LitPlane()) : scene(std::move(s)) {}
    Scene scene;
    std::unique_ptr<EmbreeScene> embree = EmbreeScene::Build(scene).value();
    Camera camera{scene.camera, embree->origin()};
    Camera world{scene.camera, Vec3d()};  // rays in scene coordinates, for the expected values
};

bool SameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

Image Render(const Prepared& p, const RadianceEstimator& estimator, uint64_t spp, uint32_t aovs) {
    RenderSettings settings;
    settings.spp = spp;
    settings.tile = 8;
    settings.aovs = aovs;
    return RenderImage(p.camera, estimator, settings).value().image;
}

// Every pixel within 1% of its expected lux plus `standard_errors` times the standard error of
// a mean of `spp` samples; the pixel under the light (the image's middle) reads I / h^2 and the
// corners (50 degrees off the axis) I cos^3(theta) / h^2, about 0.28 of it.
void ExpectInverseSquareCosineCubed(const Prepared& p, const Image& image, uint64_t spp,
                                    double standard_errors, double sigma_a = 0) {
    const int n = kSize;
    const std::vector<float>& lux = *image.FindChannel(kAovIlluminanceChannel);
    double worst = 0;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const PixelLux e = ExpectedPixel(p.world, x, y, sigma_a);
            const double got = lux[size_t(y) * n + x];
            const double tolerance = 0.01 * e.mean + standard_errors * e.sd / std::sqrt(spp);
            ASSERT_NEAR(got, e.mean, tolerance) << "pixel " << x << "," << y;
            worst = std::max(worst, std::abs(got / e.mean - 1));
        }
    }
    // The middle pixel's footprint (0.2 wide) averages 0.3 % below the value under the light.
    const double below = kCandela / (kHeight * kHeight) * std::exp(-sigma_a * kHeight);
    EXPECT_NEAR(lux[size_t(n / 2) * n + n / 2], below, 0.01 * below);
    EXPECT_LT(ExpectedPixel(p.world, 0, 0, sigma_a).mean, 0.5 * below);
    std::printf("worst relative error %.5f, middle pixel %.3f lux, corner %.3f lux\n", worst,
                lux[size_t(n / 2) * n + n / 2], lux[0]);
}

TEST(Illuminance, RadiosityPlaneUnderAPointLightIsInverseSquareCosineCubed) {
    const Prepared p;
    RadiosityOptions options;
    options.patch_size = 0.1;
    const std::unique_ptr<RadiosityRenderer> radiosity =
        PrepareRadiosity(*p.embree, options).value();
    // The solution is exact at each sample's position: the only randomness is that position,
    // 4 standard errors of it.
    constexpr uint64_t kSpp = 64;
    ExpectInverseSquareCosineCubed(p, Render(p, *radiosity, kSpp, kAovIlluminance), kSpp, 4);
}

// Where a channel of the reflectance is 0 the radiosity says nothing about the light arriving:
// the solve carries the irradiance itself, so the black strip and the red strip's green and blue
// read the grey strip's lux (they read 0 and a third of it when it was (B - E) / ρ), flat and
// hierarchical, in the image and in the PLY.
TEST(Illuminance, RadiosityReadsTheLightArrivingWhereTheReflectanceIsZero) {
    const Prepared p(LitPlaneOfThreeAlbedos());
    const std::string ply = ::testing::TempDir() + "/illuminance_three_albedos.ply";
    for (const bool hierarchical : {false, true}) {
        SCOPED_TRACE(hierarchical ? "hierarchical" : "flat");
        RadiosityOptions options;
        options.patch_size = 0.1;
        options.hierarchical = hierarchical;
        options.export_ply = ply;
        const std::unique_ptr<RadiosityRenderer> radiosity =
            PrepareRadiosity(*p.embree, options).value();
        constexpr uint64_t kSpp = 64;
        const Image image = Render(p, *radiosity, kSpp, kAovIlluminance);
        ExpectInverseSquareCosineCubed(p, image, kSpp, 4);
        // The black strip under the light is black, the red one has no green.
        const int n = kSize;
        const std::vector<float>& green = *image.FindChannel("G");
        EXPECT_EQ(green[size_t(n / 2) * n + n / 2], 0.f);
        const Ray edge = p.world.GenerateRay(0, n / 2, 0.5f, 0.5f);
        const int red_x = edge.o.x - edge.d.x * (edge.o.y / edge.d.y) > 0 ? 0 : n - 1;
        EXPECT_EQ(green[size_t(n / 2) * n + red_x], 0.f);

        // Every PLY vertex (x y z red green blue lux) on all three strips, but for those on
        // a strip's edge, whose corner means are one-sided (the display's O(h) there).
        std::ifstream in(ply);
        std::string line;
        int vertices = 0;
        while (std::getline(in, line) && line != "end_header") {
            std::sscanf(line.c_str(), "element vertex %d", &vertices);
        }
        ASSERT_GT(vertices, 0);
        int checked[3] = {};
        double x, y, z, lux;
        int r, g, b;
        for (int v = 0; v < vertices && in >> x >> y >> z >> r >> g >> b >> lux; ++v) {
            if (std::abs(z) > 1.99 || std::abs(std::abs(x) - 2) < 0.01 ||
                std::abs(std::abs(x) - 2.0 / 3) < 0.01) {
                continue;
            }
            const double expected = ExpectedLux(Vec3d(x, y, z), 0);
            ASSERT_NEAR(lux, expected, 0.01 * expected) << x << " " << z;
            ++checked[x < -0.7 ? 0 : x > 0.7 ? 2 : 1];
        }
        for (int k = 0; k < 3; ++k) EXPECT_GT(checked[k], 100) << "strip " << k;
    }
    std::filesystem::remove(ply);
}

TEST(Illuminance, PathTracerReadsTheLightArrivingWhereTheReflectanceIsZero) {
    const Prepared p(LitPlaneOfThreeAlbedos());
    const PathTracer tracer(*p.embree, -1);
    constexpr uint64_t kSpp = 64;
    ExpectInverseSquareCosineCubed(p, Render(p, tracer, kSpp, kAovIlluminance), kSpp, 4);
}

// A small lamp panel (radiance Le, black: ρ = 0) at height h facing a floor of albedo ρ that it
// lights: the floor sends back E(q) = ρ Le A h^2 / r^4 as radiosity, and the panel receives
// ∫ ρ Le A h^4 / (π r^8) dA = ρ Le A / (3 h^2) over the plane (r^2 = h^2 + q^2). Within 1 %: the
// panel is 1/20 of h across (its finite size is a 0.3 % correction) and the 10 x 10 floor
// misses 1e-4 of the integral. (B - E) / ρ gave the panel 0. Flat only: the hierarchy bounds
// each link's power by link_error of the scene's, an absolute bound, and the panel gathers about
// that much in all (22 % low at 1e-4, 1.1 % at 1e-6; docs/radiosity.md).
TEST(Illuminance, LampPanelReadsTheLightTheFloorSendsBack) {
    constexpr double kHeight = 1, kSide = 0.05, kAlbedo = 0.5, kLe = 1;
    Scene scene;
    Material floor, lamp;
    floor.reflectance = Rgb(float(kAlbedo));
    lamp.reflectance = Rgb(0);
    lamp.emission = Rgb(float(kLe));
    scene.materials = {floor, lamp};
    const auto square = [](double half, double y, int material, bool up) {
        TriangleMesh m;
        m.material = material;
        m.is_quad = true;
        m.positions = {{-half, y, -half}, {-half, y, half}, {half, y, half}, {half, y, -half}};
        m.triangles = up ? std::vector<std::array<uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}}
                         : std::vector<std::array<uint32_t, 3>>{{0, 2, 1}, {0, 3, 2}};
        return m;
    };
    scene.meshes = {square(5, 0, 0, true), square(kSide / 2, kHeight, 1, false)};
    const auto embree = EmbreeScene::Build(scene).value();
    const double expected = kAlbedo * kLe * kSide * kSide / (3 * kHeight * kHeight);
    for (const RadiositySolver solver :
         {RadiositySolver::kJacobi, RadiositySolver::kGaussSeidel, RadiositySolver::kShooting}) {
        SCOPED_TRACE(RadiositySolverName(solver));
        RadiosityOptions options;
        options.patch_size = 0.1;
        options.solver = solver;
        const std::unique_ptr<RadiosityRenderer> radiosity =
            PrepareRadiosity(*embree, options).value();
        // The panel's lit face is its front, facing down.
        const Rgb h = radiosity->display().Irradiance(1, 0, 1.0 / 3, 1.0 / 3, false);
        std::printf("panel irradiance %.6g W m^-2, expected %.6g\n", h.g, expected);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(h[c], expected, 0.01 * expected) << c;
        // Its radiosity is its emission alone.
        EXPECT_NEAR(radiosity->display().Radiance(1, 0, 1.0 / 3, 1.0 / 3, false).g, kLe, 1e-6);
    }
}

TEST(Illuminance, PathTracedPlaneUnderAPointLightIsInverseSquareCosineCubed) {
    const Prepared p;
    const PathTracer tracer(*p.embree, -1);
    // A point light's next-event estimate is exact and the hemisphere ray sees nothing, so a
    // sample's only randomness is its place in the pixel: 4 standard errors of that.
    constexpr uint64_t kSpp = 64;
    ExpectInverseSquareCosineCubed(p, Render(p, tracer, kSpp, kAovIlluminance), kSpp, 4);
}

// In a medium absorbing 0.2 per unit, the light reaching the plane is dimmed over its way from
// the light (exp(-0.2 d), d from 2 to 3.3), not over the camera ray's.
TEST(Illuminance, VolumetricPathTracerDimsItByTheMediumBetweenLightAndSurface) {
    constexpr float kSigmaA = 0.2f;
    const Prepared p(LitPlaneInAbsorber(kSigmaA));
    const VolPathTracer tracer(*p.embree, -1);
    constexpr uint64_t kSpp = 64;
    const Image with = Render(p, tracer, kSpp, kAovIlluminance);
    ExpectInverseSquareCosineCubed(p, with, kSpp, 4, kSigmaA);
    const Image plain = Render(p, tracer, kSpp, 0);
    for (const auto& [name, data] : plain.channels()) {
        EXPECT_TRUE(SameBits(data, *with.FindChannel(name))) << name;
    }
}

// Indirect light counts: in a closed furnace of albedo a lit by emission Le from every wall the
// irradiance everywhere is pi Le / (1 - a), which the path tracer's estimate must reach within
// its standard error; the image keeps its bits with the AOV.
TEST(Illuminance, PathTracerCountsIndirectLightAndLeavesTheImageAlone) {
    constexpr float kAlbedo = 0.5f, kLe = 1.0f;
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), kAlbedo, kLe, 8);
    const auto embree = EmbreeScene::Build(scene).value();
    const Camera camera(scene.camera, embree->origin());
    const PathTracer tracer(*embree, -1);
    RenderSettings settings;
    settings.spp = 64;
    settings.tile = 8;
    const Image plain = RenderImage(camera, tracer, settings).value().image;
    settings.aovs = kAllAovs | kAovIlluminance;
    const Image with = RenderImage(camera, tracer, settings).value().image;
    for (const auto& [name, data] : plain.channels()) {
        EXPECT_TRUE(SameBits(data, *with.FindChannel(name))) << name;
    }
    const testing::MeanAndError lux = testing::ChannelMean(with, kAovIlluminanceChannel);
    const double expected = kLumensPerWatt * std::numbers::pi * kLe / (1 - kAlbedo);
    EXPECT_NEAR(lux.mean, expected, 5 * lux.standard_error + 1e-3 * expected);
    EXPECT_GT(lux.standard_error, 0);
}

}  // namespace
}  // namespace lf
