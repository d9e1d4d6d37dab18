// Spot and directional lights against closed forms: a Lambertian plane of albedo rho lit by
// one light, rendered by the path tracer (next-event estimation is the only way to reach a
// delta light), and the light sampler's own answers.
#include "lf/kernels/lights.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lf/kernels/embree_scene.h"
#include "plane_render.h"
#include "render_path.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr uint64_t kSpp = 64;

double Radians(double degrees) { return degrees * kPi / 180; }

// The spot falloffs, written from their definitions: KHR_lights_punctual's recommended
// clamp((c - cos outer) / (cos inner - cos outer), 0, 1)^2, and pbrt-v4's
// smoothstep(cos outer, cos inner, c).
double SpotFalloff(double cos_to_axis, double inner, double outer, SpotLight::Falloff falloff) {
    const double scale = 1 / std::max(0.001, std::cos(inner) - std::cos(outer));
    const double a = std::clamp((cos_to_axis - std::cos(outer)) * scale, 0.0, 1.0);
    return falloff == SpotLight::Falloff::kSmoothstep ? a * a * (3 - 2 * a) : a * a;
}

const char* FalloffName(SpotLight::Falloff falloff) {
    return falloff == SpotLight::Falloff::kSmoothstep ? "smoothstep" : "khr";
}

SpotLight DownwardSpot(const Vec3d& position, const Rgb& intensity, double inner_degrees,
                       double outer_degrees,
                       SpotLight::Falloff falloff = SpotLight::Falloff::kSmoothstep) {
    SpotLight spot;
    spot.falloff = falloff;
    spot.position = position;
    spot.direction = Vec3d(0, -1, 0);
    spot.intensity = intensity;
    spot.inner_cone = Radians(inner_degrees);
    spot.outer_cone = Radians(outer_degrees);
    return spot;
}

class SpotFalloffTest : public ::testing::TestWithParam<SpotLight::Falloff> {};

INSTANTIATE_TEST_SUITE_P(Falloffs, SpotFalloffTest,
                         ::testing::Values(SpotLight::Falloff::kSmoothstep,
                                           SpotLight::Falloff::kKhrLightsPunctual),
                         [](const auto& info) { return std::string(FalloffName(info.param)); });

// A spot light at height h pointing straight down: irradiance I cos(theta) / r^2 inside the
// inner cone, zero outside the outer cone, the falloff between.
TEST_P(SpotFalloffTest, LambertianPlaneMatchesClosedForm) {
    const Rgb rho(0.5f, 0.25f, 0.75f);
    Scene scene = testing::PlaneUnderCamera(rho);
    const SpotLight spot =
        DownwardSpot(Vec3d(0.3, 1.0, -0.2), Rgb(10.0f, 5.0f, 2.0f), 25, 45, GetParam());
    scene.spot_lights.push_back(spot);
    const RenderOutput out = testing::RenderPath(scene, kSpp).out;

    int inside = 0, between = 0, outside = 0;
    const int compared = testing::ExpectPlaneMatches(scene, out.image, kSpp, [&](const Vec3d& x) {
        const Vec3d d = spot.position - x;
        const double dist2 = LengthSquared(d);
        const double cos_theta = d.y / std::sqrt(dist2);  // to the plane's normal and the axis
        const double falloff =
            SpotFalloff(cos_theta, spot.inner_cone, spot.outer_cone, spot.falloff);
        if (falloff == 1) {
            ++inside;
        } else if (falloff == 0) {
            ++outside;
        } else {
            ++between;
        }
        return rho * spot.intensity * float(falloff * cos_theta / dist2 / kPi);
    });
    EXPECT_EQ(compared, testing::kPlaneImageSize * testing::kPlaneImageSize);
    // The image spans all three regions.
    EXPECT_GT(inside, 1000);
    EXPECT_GT(between, 1000);
    EXPECT_GT(outside, 1000);

    // Outside the outer cone nothing at all: the corner pixels are 1.5 or more from the spot's
    // foot, well beyond tan(45 degrees) * 1.
    for (auto [px, py] : {std::pair(0, 0), std::pair(15, 0), std::pair(0, 15), std::pair(15, 15)}) {
        EXPECT_EQ(out.image.Pixel(px, py), Rgb(0.0f)) << px << "," << py;
    }
}

// The sampler's radiance at points swept from the axis to beyond the outer cone.
TEST_P(SpotFalloffTest, SamplerFollowsTheFalloff) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    const SpotLight spot = DownwardSpot(Vec3d(0, 2, 0), Rgb(3.0f), 10, 30, GetParam());
    scene.spot_lights.push_back(spot);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es);
    const Vec3 light = Vec3(spot.position - (*es)->origin());
    for (double angle = 0; angle < 60; angle += 0.5) {
        // A reference point below the light at `angle` off the axis, 1.5 away.
        const double a = Radians(angle);
        const Vec3 ref = light + Vec3(float(1.5 * std::sin(a)), -float(1.5 * std::cos(a)), 0);
        const std::optional<LightSample> ls = sampler.Sample(ref, 0.5f, {0.5f, 0.5f});
        const double expected =
            3 * SpotFalloff(std::cos(a), spot.inner_cone, spot.outer_cone, spot.falloff) /
            (1.5 * 1.5);
        if (expected == 0) {
            EXPECT_FALSE(ls) << angle;
            continue;
        }
        ASSERT_TRUE(ls) << angle;
        EXPECT_TRUE(ls->delta);
        EXPECT_EQ(ls->pdf, 1);
        EXPECT_NEAR(ls->radiance.g, expected, 1e-5 * expected + 1e-6) << angle;
        EXPECT_NEAR(Length(ls->wi), 1, 1e-6);
        EXPECT_NEAR(Dot(ls->wi, Normalize(light - ref)), 1, 1e-6);
    }
}

Scene DirectionalScene(const Rgb& rho, const DirectionalLight& sun) {
    Scene scene = testing::PlaneUnderCamera(rho);
    scene.directional_lights.push_back(sun);
    return scene;
}

// Under a directional light of irradiance E the plane's radiance is rho/pi E cos(theta)
// everywhere: every sample of every pixel is the same number.
TEST(DirectionalLight, LambertianPlaneMatchesClosedForm) {
    const Rgb rho(0.5f, 0.25f, 0.75f);
    const DirectionalLight sun{Normalize(Vec3d(0.3, -1, 0.2)), Rgb(2.0f, 1.0f, 0.5f)};
    const Scene scene = DirectionalScene(rho, sun);
    const RenderOutput out = testing::RenderPath(scene, kSpp).out;
    const double cos_theta = -sun.direction.y;
    const int compared = testing::ExpectPlaneMatches(scene, out.image, kSpp, [&](const Vec3d&) {
        return rho * sun.irradiance * float(cos_theta / kPi);
    });
    EXPECT_EQ(compared, testing::kPlaneImageSize * testing::kPlaneImageSize);
}

// A wall at x = -2.5, out of the camera's view, shadows the plane from light arriving at 45
// degrees from -x: the shadow ends at x = 0.5, and light reaches the plane beyond it.
TEST(DirectionalLight, OccluderCastsTheExpectedShadow) {
    const Rgb rho(0.8f);
    const DirectionalLight sun{Normalize(Vec3d(1, -1, 0)), Rgb(3.0f)};
    Scene scene = DirectionalScene(rho, sun);
    Material black;  // no light bounced back onto the plane: direct light only
    black.reflectance = Rgb(0.0f);
    scene.materials.push_back(black);
    TriangleMesh wall;
    wall.material = 1;
    wall.positions = {{-2.5, 0.01, -50}, {-2.5, 3, -50}, {-2.5, 3, 50}, {-2.5, 0.01, 50}};
    wall.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(wall);
    const RenderOutput out = testing::RenderPath(scene, kSpp).out;
    const double shadow_end = -2.5 + 3;  // the wall's top, 3 high, projected at 45 degrees
    const auto shadowed = [&](const Vec3d& x) { return x.x < shadow_end; };
    const float lit = float(-sun.direction.y / kPi);
    int dark = 0, bright = 0;
    const int compared = testing::ExpectPlaneMatches(
        scene, out.image, kSpp,
        [&](const Vec3d& x) {
            if (shadowed(x)) {
                ++dark;
                return Rgb(0.0f);
            }
            ++bright;
            return rho * sun.irradiance * lit;
        },
        [&](const Vec3d& a, const Vec3d& b) { return shadowed(a) != shadowed(b); });
    // One column of pixels straddles the edge.
    EXPECT_EQ(compared, testing::kPlaneImageSize * (testing::kPlaneImageSize - 1));
    EXPECT_GT(dark, 10000);
    EXPECT_GT(bright, 10000);
}

// The shadow ray ends beyond the scene, so geometry anywhere along it blocks the sun, however
// far from the reference point.
TEST(DirectionalLight, ShadowRayReachesBeyondTheScene) {
    Scene scene = DirectionalScene(Rgb(0.5f), {Vec3d(0, -1, 0), Rgb(1.0f)});
    TriangleMesh roof;  // far above, and far larger than the plane
    const double h = 1000, s = 5000;
    roof.positions = {{-s, h, -s}, {s, h, -s}, {s, h, s}, {-s, h, s}};
    roof.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(roof);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es);
    for (const Vec3d& world : {Vec3d(0, 0, 0), Vec3d(40, 0, -30), Vec3d(-45, 0, 45)}) {
        const SurfacePoint here{Vec3(world - (*es)->origin()), Vec3(1e-4f, 1e-4f, 1e-4f),
                                Vec3(0, 1, 0)};
        const std::optional<LightSample> ls = sampler.Sample(here.p, 0.5f, {0.5f, 0.5f});
        ASSERT_TRUE(ls);
        EXPECT_TRUE(ls->delta);
        EXPECT_EQ(ls->radiance, Rgb(1.0f));
        EXPECT_NEAR(ls->wi.y, 1, 1e-6);
        EXPECT_TRUE((*es)->Occluded(SpawnRayTo(here, ls->point)));
    }
}

// The solid angle a spot's falloff integrates to, 2 pi times its integral over cos(theta), by
// the midpoint rule.
double SpotSolidAngle(const SpotLight& spot) {
    constexpr int kSteps = 100000;
    double sum = 0;
    for (int i = 0; i < kSteps; ++i) {
        const double c = -1 + 2 * (i + 0.5) / kSteps;
        sum += SpotFalloff(c, spot.inner_cone, spot.outer_cone, spot.falloff);
    }
    return 2 * kPi * sum * 2 / kSteps;
}

// Picking follows power: a spot ~ its falloff's solid angle times I, a directional light
// ~ pi R^2 E with R the scene's bounding radius, a point light 4 pi I.
TEST(LightSampler, PicksDeltaLightsByPower) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));  // bounds 100 x 0 x 100: R = 50 sqrt 2
    scene.point_lights.push_back({Vec3d(0, 1, 0), Rgb(1.0f)});
    const SpotLight spot = DownwardSpot(Vec3d(1, 1, 0), Rgb(100.0f), 20, 40);
    scene.spot_lights.push_back(spot);
    scene.directional_lights.push_back({Vec3d(0, -1, 0), Rgb(0.001f)});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es);
    const double w_point = 4 * kPi;
    const double w_spot = SpotSolidAngle(spot) * 100;
    const double r = 50 * std::sqrt(2.0);
    const double w_sun = kPi * r * r * 0.001;
    const double total = w_point + w_spot + w_sun;
    // Reference point under all three; the pdf of a delta light is its pick probability.
    const Vec3 ref = Vec3(Vec3d(0.5, 0.1, 0) - (*es)->origin());
    int seen = 0;
    for (int i = 0; i < 1000; ++i) {
        const auto ls = sampler.Sample(ref, (i + 0.5f) / 1000, {0.5f, 0.5f});
        ASSERT_TRUE(ls);
        ++seen;
        const bool is_sun = ls->wi.y > 0.999f && ls->radiance == Rgb(0.001f);
        const double expected = is_sun                ? w_sun / total
                                : ls->radiance.g > 10 ? w_spot / total
                                                      : w_point / total;
        EXPECT_NEAR(ls->pdf, expected, 1e-6) << i;
    }
    EXPECT_EQ(seen, 1000);
}

}  // namespace
}  // namespace lf
