// Radiosity lit by the lights modelling tools export: point, spot (both falloffs), directional
// (delta and sun disk) and sky lights enter as direct irradiance on each patch side, checked
// against their closed forms through RadiosityDisplay::Irradiance. A lone plane (or a black
// occluder) has no interreflection, so the irradiance is exactly the direct one.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lf/core/film.h"
#include "lf/core/sampler.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiosity.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// A horizontal square of half-width `half` at y = 0, normal +y.
TriangleMesh Floor(double half) {
    TriangleMesh quad;
    quad.name = "floor";
    quad.is_quad = true;
    quad.positions = {{-half, 0, -half}, {-half, 0, half}, {half, 0, half}, {half, 0, -half}};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    return quad;
}

// An axis-aligned closed box of material `material`.
TriangleMesh Box(const Vec3d& lo, const Vec3d& hi, int material) {
    TriangleMesh box;
    box.name = "box";
    box.material = material;
    for (int i = 0; i < 8; ++i) {
        box.positions.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
    }
    box.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return box;
}

Scene PlaneScene(double half) {
    Scene scene;
    Material floor;
    floor.name = "floor";
    floor.reflectance = Rgb(0.5f, 0.4f, 0.3f);
    scene.materials.push_back(floor);
    scene.meshes.push_back(Floor(half));
    return scene;
}

struct Solved {
    std::unique_ptr<EmbreeScene> embree;
    std::unique_ptr<RadiosityRenderer> renderer;

    // The irradiance on the upper side of the floor at the centroid of the patch holding
    // (x, z), and that centroid.
    std::pair<Rgb, Vec3d> At(double x, double z) const {
        const PatchMesh& mesh = renderer->mesh();
        const TriangleMesh& floor = embree->scene().meshes[0];
        for (int t = 0; t < 2; ++t) {
            const Vec3d& a = floor.positions[floor.triangles[size_t(t)][0]];
            const Vec3d& b = floor.positions[floor.triangles[size_t(t)][1]];
            const Vec3d& c = floor.positions[floor.triangles[size_t(t)][2]];
            // Barycentrics of (x, z) in the xz-plane.
            const double det = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
            const double b1 = ((x - a.x) * (c.z - a.z) - (c.x - a.x) * (z - a.z)) / det;
            const double b2 = ((b.x - a.x) * (z - a.z) - (x - a.x) * (b.z - a.z)) / det;
            if (b1 < 0 || b2 < 0 || b1 + b2 > 1) continue;
            const PatchPoint p = mesh.Locate(0, t, b1, b2);
            const auto [c1, c2] = mesh.TriangleBarycentrics(p.patch, {1.0 / 3, 1.0 / 3, 1.0 / 3});
            return {renderer->display().Irradiance(0, t, c1, c2, false), mesh.Centroid(p.patch)};
        }
        ADD_FAILURE() << "(" << x << ", " << z << ") is off the floor";
        return {};
    }
};

// The scene must outlive the result.
Solved Solve(const Scene& scene, int64_t patches) {
    Solved s;
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    s.embree = std::move(*es);
    RadiosityOptions options;
    options.patches = patches;
    options.display = RadiosityShading::kFlat;
    auto renderer = PrepareRadiosity(*s.embree, options);
    EXPECT_TRUE(renderer.ok()) << renderer.status();
    if (renderer.ok()) s.renderer = std::move(*renderer);
    return s;
}

void ExpectNear(const Rgb& got, const Rgb& expected, double relative, const char* what) {
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(got[c], expected[c], relative * expected[c]) << what << " channel " << c;
    }
}

// I cos^3 / h^2 at the patch centroid: the patch average differs from it by the curvature only,
// below 0.3 % at these patch sizes.
Rgb PointIrradiance(const Rgb& intensity, const Vec3d& light, const Vec3d& x) {
    const Vec3d d = light - x;
    return intensity * float(d.y / std::pow(LengthSquared(d), 1.5));
}

TEST(RadiosityLights, PointLightFollowsTheInverseSquareAndCosineCubedLaws) {
    Scene scene = PlaneScene(4);
    const Rgb intensity(2, 3, 4);
    const Vec3d light(0, 2, 0);
    scene.point_lights.push_back({light, intensity});
    const Solved s = Solve(scene, 4096);
    ASSERT_TRUE(s.renderer);
    for (const auto& [x, z] : {std::pair{0.0, 0.0}, {2.0, 0.0}, {1.0, -1.5}}) {
        const auto [got, centroid] = s.At(x, z);
        ExpectNear(got, PointIrradiance(intensity, light, centroid), 0.01, "point");
    }
    // Right below: I / h^2.
    ExpectNear(s.At(0, 0).first, intensity * 0.25f, 0.01, "below");
}

TEST(RadiosityLights, SpotLightIsAPointLightInsideItsInnerConeAndDarkOutsideItsOuter) {
    for (const SpotLight::Falloff falloff :
         {SpotLight::Falloff::kSmoothstep, SpotLight::Falloff::kKhrLightsPunctual}) {
        Scene scene = PlaneScene(4);
        SpotLight spot;
        spot.position = Vec3d(0, 2, 0);
        spot.direction = Vec3d(0, -1, 0);
        spot.intensity = Rgb(5, 4, 3);
        spot.inner_cone = 30 * kPi / 180;
        spot.outer_cone = 40 * kPi / 180;
        spot.falloff = falloff;
        scene.spot_lights.push_back(spot);
        const Solved s = Solve(scene, 4096);
        ASSERT_TRUE(s.renderer);
        for (const auto& [x, z] : {std::pair{0.0, 0.0}, {0.7, 0.3}, {-0.5, -0.6}}) {
            const auto [got, centroid] = s.At(x, z);
            ExpectNear(got, PointIrradiance(spot.intensity, spot.position, centroid), 0.01,
                       "inside the inner cone");
        }
        // 51 and 56 degrees off the axis: past the outer cone (40 degrees) by more than a patch.
        for (const auto& [x, z] : {std::pair{2.5, 0.0}, {-2.0, -2.0}}) {
            EXPECT_EQ(s.At(x, z).first.MaxComponent(), 0) << x << ", " << z;
        }
    }
}

TEST(RadiosityLights, SunLightsTheGroundByTheSineOfItsElevationAndABoxShadowsIt) {
    const double elevation = 35 * kPi / 180;
    const Rgb e(3, 2, 1);
    for (const double diameter : {0.0, 0.05}) {
        Scene scene = PlaneScene(4);
        Material black;
        black.name = "black";
        black.reflectance = Rgb(0.0f);
        scene.materials.push_back(black);
        // Light travels towards -x and down: the box casts its shadow towards -x.
        scene.meshes.push_back(Box({1.0, 0.0, -0.5}, {2.0, 1.0, 0.5}, 1));
        scene.directional_lights.push_back(
            {Vec3d(-std::cos(elevation), -std::sin(elevation), 0), e, diameter});
        const Solved s = Solve(scene, 4096);
        ASSERT_TRUE(s.renderer);
        const Rgb lit = e * float(std::sin(elevation));
        for (const auto& [x, z] : {std::pair{-2.0, 2.0}, {3.0, 0.0}, {0.0, -2.5}}) {
            ExpectNear(s.At(x, z).first, lit, 0.01, diameter > 0 ? "sun disk" : "directional");
        }
        // The box's top is 1 high: its shadow reaches 1 / tan(35°) = 1.43 beyond its -x face,
        // from x = 1 to -0.43; well inside it, nothing.
        EXPECT_EQ(s.At(0.5, 0.0).first.MaxComponent(), 0);
        EXPECT_EQ(s.At(-0.1, 0.2).first.MaxComponent(), 0);
    }
}

TEST(RadiosityLights, UniformSkyLightsAnOpenPlaneByPiL) {
    Scene scene = PlaneScene(2);
    EnvironmentLight sky;
    sky.radiance = Rgb(0.2f, 0.5f, 1.0f);
    scene.environment = sky;
    const Solved s = Solve(scene, 256);
    ASSERT_TRUE(s.renderer);
    for (const auto& [x, z] : {std::pair{0.0, 0.0}, {1.5, -1.2}}) {
        ExpectNear(s.At(x, z).first, sky.radiance * float(kPi), 0.01, "sky");
    }
    // Rays that leave the scene see the sky, as the path tracer shows it.
    Sampler sampler(1, 0, 0, 0);
    RenderStats stats;
    const Ray up{Vec3(0, 1, 0), Vec3(0, 1, 0)};
    ExpectNear(s.renderer->display().Li(up, sampler, stats), sky.radiance, 1e-6, "background");
}

// A latitude-longitude map (2 x 4 texels): the upper hemisphere 1 towards -z and 3 towards +z,
// the lower 0.5. An open plane's upper side gets pi times the cosine-weighted mean, 2 pi (each
// half of the azimuths carries half the cosine weight), its lower side pi / 2.
TEST(RadiosityLights, SkyMapLightsEachSideByItsHemisphere) {
    Scene scene = PlaneScene(2);
    auto map = std::make_shared<TextureImage>();
    map->name = "sky.hdr";
    map->width = 4;
    map->height = 2;
    map->channels = 3;
    map->hdr = true;
    for (const float v : {1.f, 1.f, 3.f, 3.f, 0.5f, 0.5f, 0.5f, 0.5f}) {
        map->texels32.insert(map->texels32.end(), {v, v, v});
    }
    EnvironmentLight sky;
    sky.map = map;
    scene.environment = sky;
    const Solved s = Solve(scene, 256);
    ASSERT_TRUE(s.renderer);
    const PatchMesh& mesh = s.renderer->mesh();
    const RadiosityDisplay& display = s.renderer->display();
    const auto [b1, b2] = mesh.TriangleBarycentrics(0, {1.0 / 3, 1.0 / 3, 1.0 / 3});
    EXPECT_NEAR(display.Irradiance(0, 0, b1, b2, false).g, 2 * kPi, 0.01 * 2 * kPi);
    EXPECT_NEAR(display.Irradiance(0, 0, b1, b2, true).g, 0.5 * kPi, 0.01 * 0.5 * kPi);
}

// The form factor from a point to a parallel rectangle with a corner right above it, sides a and
// b, at height h (the classic corner formula).
double CornerFormFactor(double a, double b, double h) {
    const double x = a / h, y = b / h;
    return (x / std::sqrt(1 + x * x) * std::atan(y / std::sqrt(1 + x * x)) +
            y / std::sqrt(1 + y * y) * std::atan(x / std::sqrt(1 + y * y))) /
           (2 * kPi);
}

// A uniform sky over a floor under a black roof: a point under the roof sees the sky but for
// the roof's form factor, E = pi L (1 - F).
TEST(RadiosityLights, SkyIsShadowedByARoof) {
    Scene scene = PlaneScene(3);
    Material black;
    black.name = "black";
    black.reflectance = Rgb(0.0f);
    scene.materials.push_back(black);
    // A thin roof 2 wide (x) and 6 long (z), its underside 1 high.
    scene.meshes.push_back(Box({-1.0, 1.0, -3.0}, {1.0, 1.01, 3.0}, 1));
    EnvironmentLight sky;
    sky.radiance = Rgb(1.0f);
    scene.environment = sky;
    const Solved s = Solve(scene, 4096);
    ASSERT_TRUE(s.renderer);
    for (const auto& [x, z] : {std::pair{0.0, 0.0}, {0.5, 1.0}, {-0.3, -2.0}}) {
        const auto [got, c] = s.At(x, z);
        const double f =
            CornerFormFactor(1 - c.x, 3 - c.z, 1) + CornerFormFactor(1 + c.x, 3 - c.z, 1) +
            CornerFormFactor(1 - c.x, 3 + c.z, 1) + CornerFormFactor(1 + c.x, 3 + c.z, 1);
        const double expected = kPi * (1 - f);
        EXPECT_NEAR(got.r, expected, 0.01 * expected) << x << ", " << z;
    }
}

// The lights' sample directions are fixed sequences, not per-thread random numbers: one thread
// and two give the same bits.
TEST(RadiosityLights, SameSolutionForAnyThreadCount) {
    Scene scene = PlaneScene(3);
    Material grey;
    grey.reflectance = Rgb(0.3f);
    scene.materials.push_back(grey);
    scene.meshes.push_back(Box({-1.0, 1.0, -1.0}, {1.0, 1.2, 1.0}, 1));
    scene.environment = EnvironmentLight{};
    scene.directional_lights.push_back({Vec3d(-0.3, -1, 0.2), Rgb(2.0f), 0.05});
    scene.spot_lights.push_back(
        {.position = {0.5, 0.8, 0}, .direction = {0, -1, 0}, .intensity = Rgb(3.0f)});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    std::vector<std::vector<Rgb>> solutions;
    for (const int threads : {1, 2}) {
        RadiosityOptions options;
        options.patches = 512;
        options.threads = threads;
        auto renderer = PrepareRadiosity(**es, options);
        ASSERT_TRUE(renderer.ok()) << renderer.status();
        solutions.emplace_back((*renderer)->radiosity().begin(), (*renderer)->radiosity().end());
    }
    EXPECT_EQ(solutions[0], solutions[1]);
}

}  // namespace
}  // namespace lf
