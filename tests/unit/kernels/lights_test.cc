// Spot and directional lights against closed forms: a Lambertian plane of albedo rho lit by
// one light, rendered by the path tracer (next-event estimation is the only way to reach a
// delta light), and the light sampler's own answers.
#include "lf/kernels/lights.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "plane_render.h"
#include "point_estimate.h"
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
    const double scale = 1 / (std::cos(inner) - std::cos(outer));
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
// A light sample at a point 1.5 below `spot` (at `light`, in render space) and `degrees` off its
// axis, and the radiance the closed form gives there: intensity (green) times falloff / r^2.
struct SpotProbe {
    Vec3 ref;
    std::optional<LightSample> sample;
    double expected;
};
SpotProbe ProbeSpot(const LightSampler& sampler, const Vec3& light, const SpotLight& spot,
                    double degrees, float u_pick) {
    const double a = Radians(degrees);
    const Vec3 ref = light + Vec3(float(1.5 * std::sin(a)), -float(1.5 * std::cos(a)), 0);
    return {ref, sampler.Sample(ref, Vec3(0, 1, 0), u_pick, {0.5f, 0.5f}, 0),
            spot.intensity.g *
                SpotFalloff(std::cos(a), spot.inner_cone, spot.outer_cone, spot.falloff) /
                (1.5 * 1.5)};
}

TEST_P(SpotFalloffTest, SamplerFollowsTheFalloff) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    const SpotLight spot = DownwardSpot(Vec3d(0, 2, 0), Rgb(3.0f), 10, 30, GetParam());
    scene.spot_lights.push_back(spot);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es);
    const Vec3 light = Vec3(spot.position - (*es)->origin());
    for (double angle = 0; angle < 60; angle += 0.5) {
        const auto [ref, ls, expected] = ProbeSpot(sampler, light, spot, angle, 0.5f);
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

// Cones of a degree or two, where cos(inner) and cos(outer) differ by less than 1e-3 and a float
// cosine barely tells them apart: the falloff is still full on the axis and follows its formula
// across the band, and the light is picked with its exact share of the power (beside a point
// light of known power).
TEST_P(SpotFalloffTest, NarrowConesKeepTheirFalloffAndTheirShareOfThePower) {
    for (const auto& [inner, outer] : {std::pair{0.0, 1.0}, {0.5, 1.0}, {1.4, 1.5}}) {
        Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
        const SpotLight spot = DownwardSpot(Vec3d(0, 2, 0), Rgb(3.0f), inner, outer, GetParam());
        scene.spot_lights.push_back(spot);
        scene.point_lights.push_back({Vec3d(1, 2, 0), Rgb(0.01f)});
        auto es = EmbreeScene::Build(scene);
        ASSERT_TRUE(es.ok());
        const LightSampler sampler(**es, LightStrategy::kPower);
        const Vec3 light = Vec3(spot.position - (*es)->origin());

        // Power shares: 4 pi I for the point; 2 pi (1 - cos inner + band * mean) I for the
        // spot, the band (cos inner - cos outer) weighted by the falloff's mean (1/2 or 1/3).
        const double mean = GetParam() == SpotLight::Falloff::kSmoothstep ? 0.5 : 1.0 / 3;
        const double band = std::cos(Radians(inner)) - std::cos(Radians(outer));
        const double spot_weight = 2 * kPi * (1 - std::cos(Radians(inner)) + band * mean) * 3;
        const double point_weight = 4 * kPi * 0.01;
        const double spot_pmf = spot_weight / (spot_weight + point_weight);
        // The point light comes first in the sampler's order, the spot last.
        const std::optional<LightSample> on_axis =
            sampler.Sample(light - Vec3(0, 1.5f, 0), Vec3(0, 1, 0), 0.9999f, {0.5f, 0.5f}, 0);
        ASSERT_TRUE(on_axis) << inner << ".." << outer;
        EXPECT_NEAR(on_axis->pdf, spot_pmf, 1e-5 * spot_pmf) << inner << ".." << outer;
        EXPECT_NEAR(on_axis->radiance.g, 3 / (1.5 * 1.5), 1e-5) << inner << ".." << outer;

        for (double angle = 0; angle < outer + 0.2; angle += 0.05) {
            const auto [ref, ls, expected] = ProbeSpot(sampler, light, spot, angle, 0.9999f);
            // 2e-3 of the peak: a float direction resolves angles of a degree to about 1e-6
            // rad, which moves the falloff by up to (1e-6 / band width in rad) of its range.
            const double got = ls ? ls->radiance.g : 0;
            EXPECT_NEAR(got, expected, 2e-3 * 3 / (1.5 * 1.5))
                << inner << ".." << outer << " at " << angle;
        }
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
        const std::optional<LightSample> ls = sampler.Sample(here.p, here.n, 0.5f, {0.5f, 0.5f}, 0);
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

// Picking follows power (LightStrategy::kPower): a spot ~ its falloff's solid angle times I, a
// directional light ~ pi R^2 E with R the scene's bounding radius, a point light 4 pi I.
TEST(LightSampler, PicksDeltaLightsByPower) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));  // bounds 100 x 0 x 100: R = 50 sqrt 2
    scene.point_lights.push_back({Vec3d(0, 1, 0), Rgb(1.0f)});
    const SpotLight spot = DownwardSpot(Vec3d(1, 1, 0), Rgb(100.0f), 20, 40);
    scene.spot_lights.push_back(spot);
    scene.directional_lights.push_back({Vec3d(0, -1, 0), Rgb(0.001f)});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es, LightStrategy::kPower);
    const double w_point = 4 * kPi;
    const double w_spot = SpotSolidAngle(spot) * 100;
    const double r = 50 * std::sqrt(2.0);
    const double w_sun = kPi * r * r * 0.001;
    const double total = w_point + w_spot + w_sun;
    // Reference point under all three; the pdf of a delta light is its pick probability.
    const Vec3 ref = Vec3(Vec3d(0.5, 0.1, 0) - (*es)->origin());
    int seen = 0;
    for (int i = 0; i < 1000; ++i) {
        const auto ls = sampler.Sample(ref, Vec3(0, 1, 0), (i + 0.5f) / 1000, {0.5f, 0.5f}, 0);
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

// The sun's apparent diameter.
const double kSunDiameter = Radians(0.53);

// A sun disk puts the delta light's irradiance on an unoccluded plane: the integral of a
// uniform L = E / (pi sin^2 alpha) times cos over the cone is L pi sin^2(alpha) cos(theta0).
TEST(SunDisk, UnoccludedPlaneReceivesTheDeltaLightsIrradiance) {
    const Rgb rho(0.5f, 0.25f, 0.75f);
    const Vec3d direction = Normalize(Vec3d(0.3, -1, 0.2));
    const Scene scene = DirectionalScene(rho, {direction, Rgb(2.0f, 1.0f, 0.5f), kSunDiameter});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const PathTracer tracer(**es, -1);
    const Rgb expected = rho * Rgb(2.0f, 1.0f, 0.5f) * float(-direction.y / kPi);
    for (const Vec3d& x : {Vec3d(0, 0, 0), Vec3d(0.7, 0, -1.1)}) {
        testing::ExpectEstimateNear(
            testing::EstimateRadiance(
                tracer, testing::RayBetween(Vec3d(0, 3, 0), x, (*es)->origin()), 2000),
            expected);
    }
}

// A sun disk of 40 degrees at 20 degrees from the zenith (a cap entirely above the horizon,
// so the plane receives E cos(theta0) from it), optionally in front of a uniform sky, over a
// Lambertian plane: the path tracer's radiance against the closed form.
void ExpectWideSunOverPlane(const std::optional<Rgb>& sky) {
    const Rgb rho(0.5f, 0.25f, 0.75f), e(2.0f, 1.0f, 0.5f);
    const double theta0 = Radians(20);
    const Vec3d direction(-std::sin(theta0), -std::cos(theta0), 0);
    Scene scene = DirectionalScene(rho, {direction, e, Radians(40)});
    if (sky) scene.environment = EnvironmentLight{*sky, nullptr, 0};
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const PathTracer tracer(**es, -1);
    testing::ExpectEstimateNear(
        testing::EstimateRadiance(
            tracer, testing::RayBetween(Vec3d(0, 3, 0), Vec3d(0.4, 0, 0.3), (*es)->origin()), 4000),
        rho * (e * float(std::cos(theta0) / kPi) + sky.value_or(Rgb(0.0f))));
}

// A disk 40 degrees across, 20 degrees off the zenith, entirely above the horizon: still
// E cos(theta0) on the plane. BSDF samples hit so wide a disk often, so this checks their MIS
// combination with the light samples.
TEST(SunDisk, WideDiskCombinesLightAndBsdfSamples) { ExpectWideSunOverPlane(std::nullopt); }

// A uniform sky behind a wide sun: light samples and escaping BSDF rays weigh the two lights
// at infinity as one, so where they overlap nothing is lost or counted twice. The plane
// receives pi L from the sky besides the disk's irradiance.
TEST(SunDisk, SkyBehindAWideDiskAddsUp) { ExpectWideSunOverPlane(Rgb(0.3f, 0.4f, 0.5f)); }

// A disk too small for float (its radiance E / (pi sin^2 alpha) would overflow) is sampled as
// the delta light it is indistinguishable from.
TEST(SunDisk, VanishingDiskIsTheDeltaLight) {
    const Scene scene = DirectionalScene(Rgb(0.5f), {Vec3d(0, -1, 0), Rgb(1.0f), 1e-30});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es);
    const auto ls = sampler.Sample(Vec3(0, 0, 0), Vec3(0, 1, 0), 0.5f, {0.5f, 0.5f}, 0);
    ASSERT_TRUE(ls);
    EXPECT_TRUE(ls->delta);
    EXPECT_EQ(ls->radiance, Rgb(1.0f));
    EXPECT_EQ(sampler.EscapedRadiance(Vec3(0, 1, 0)), Rgb(0.0f));
}

// A camera ray (or a mirror's) into the disk sees its radiance E / (pi sin^2 alpha); a ray just
// outside it sees nothing.
TEST(SunDisk, RaysIntoTheDiskSeeItsRadiance) {
    Scene scene = DirectionalScene(Rgb(0.5f), {Vec3d(0, -1, 0), Rgb(3.0f), kSunDiameter});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const PathTracer tracer(**es, -1);
    const double alpha = kSunDiameter / 2;
    const double radiance = 3 / (kPi * std::sin(alpha) * std::sin(alpha));
    const auto seen = [&](double angle) {
        const Vec3d from(0, 1, 0), to = from + Vec3d(std::sin(angle), std::cos(angle), 0);
        return testing::EstimateRadiance(tracer, testing::RayBetween(from, to, (*es)->origin()), 1)
            .mean[0];
    };
    EXPECT_NEAR(seen(0), radiance, 1e-5 * radiance);
    EXPECT_NEAR(seen(0.9 * alpha), radiance, 1e-5 * radiance);
    EXPECT_EQ(seen(1.1 * alpha), 0);
}

// The sun at the zenith over a plane, and a black half-plane x < 0 at height h. In gnomonic
// coordinates (w.x / w.y, w.z / w.y) the disk is a circle of radius r = tan(alpha), and from
// ground point x the occluder hides w.x / w.y < -x / h: a straight chord at distance d = x / h
// from the centre, on the lit side. The visible fraction of the (to 1e-5 uniform) disk is
// f = (acos(-d / r) + (d / r) sqrt(1 - (d / r)^2)) / pi: 0 for x <= -h r, 1/2 at the edge's
// foot, 1 for x >= h r, a penumbra 2 h tan(alpha) wide.
TEST(SunDisk, EdgeCastsPenumbraOfPredictedWidth) {
    const Rgb rho(0.8f);
    const double h = 1, r = std::tan(kSunDiameter / 2);
    Scene scene = DirectionalScene(rho, {Vec3d(0, -1, 0), Rgb(3.0f), kSunDiameter});
    Material black;
    black.reflectance = Rgb(0.0f);
    scene.materials.push_back(black);
    TriangleMesh roof;
    roof.material = 1;
    roof.positions = {{-50, h, -50}, {0, h, -50}, {0, h, 50}, {-50, h, 50}};
    roof.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(roof);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const PathTracer tracer(**es, -1);
    const float full = float(3 / kPi) * rho.r;
    for (const double q : {-1.5, -1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 1.0, 1.5}) {
        const double x = q * h * r;
        const double f = q <= -1  ? 0
                         : q >= 1 ? 1
                                  : (std::acos(-q) + q * std::sqrt(1 - q * q)) / kPi;
        // Seen from below the roof's height, so the camera ray passes under it.
        const testing::PointEstimate got = testing::EstimateRadiance(
            tracer, testing::RayBetween(Vec3d(x + 0.5, 0.5, 0.1), Vec3d(x, 0, 0), (*es)->origin()),
            4000);
        testing::ExpectEstimateNear(got, Rgb(float(f) * full));
        if (f == 0) {
            EXPECT_EQ(got.mean[0], 0) << q;
        } else if (f == 1) {
            EXPECT_NEAR(got.mean[0], full, 1e-4 * full) << q;
        }
    }
}

// A square emitter of radiance Le, 2a on a side, a distance h above the point under its
// centre: that point's irradiance is pi Le F, with F four times the view factor of a parallel
// rectangle X = a / h by Y = a / h from beneath its corner,
// (X / sqrt(1 + X^2) atan(Y / sqrt(1 + X^2)) + Y / sqrt(1 + Y^2) atan(X / sqrt(1 + Y^2))) / 2 pi.
double UnderSquareViewFactor(double a, double h) {
    const double x = a / h, sx = std::sqrt(1 + x * x);
    return 4 * (2 * x / sx * std::atan(x / sx)) / (2 * kPi);
}

// A black emitting square at y = 1 whose front faces up, over a plane at y = 0. One-sided it
// leaves the plane dark and looks black from below; two-sided it lights the plane as a
// downward-facing one would, rho Le F, and looks Le from either side.
TEST(TwoSidedEmitter, GlowsAndLightsFromBothSides) {
    const Rgb rho(0.5f, 0.25f, 0.75f), le(2.0f, 3.0f, 4.0f);
    const double a = 0.5, h = 1;
    for (const bool two_sided : {false, true}) {
        Scene scene = testing::PlaneUnderCamera(rho);
        Material panel;
        panel.reflectance = Rgb(0.0f);
        panel.emission = le;
        panel.two_sided_emission = two_sided;
        scene.materials.push_back(panel);
        TriangleMesh square;
        square.material = 1;
        square.positions = {{-a, h, -a}, {-a, h, a}, {a, h, a}, {a, h, -a}};  // normal +y
        square.triangles = {{0, 1, 2}, {0, 2, 3}};
        scene.meshes.push_back(square);
        auto es = EmbreeScene::Build(scene);
        ASSERT_TRUE(es.ok());
        const PathTracer tracer(**es, -1);
        const Vec3d& origin = (*es)->origin();
        const auto look = [&](const Vec3d& from, const Vec3d& to, int n) {
            return testing::EstimateRadiance(tracer, testing::RayBetween(from, to, origin), n);
        };
        // From above, the front; from below (beside the plane's lit point), the back.
        const testing::PointEstimate front = look(Vec3d(0.1, 3, 0), Vec3d(0.1, h, 0), 1);
        const testing::PointEstimate back = look(Vec3d(0.1, 0.5, 0), Vec3d(0.1, h, 0), 1);
        const testing::PointEstimate floor = look(Vec3d(0.8, 0.5, 0), Vec3d(0, 0, 0), 4000);
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(front.mean[c], le[c]);
            EXPECT_EQ(back.mean[c], two_sided ? le[c] : 0) << two_sided;
        }
        if (two_sided) {
            testing::ExpectEstimateNear(floor, rho * le * float(UnderSquareViewFactor(a, h)));
        } else {
            for (int c = 0; c < 3; ++c) EXPECT_EQ(floor.mean[c], 0);
        }
    }
}

// Lights at infinity and two-sided emitters are picked by power too (kPower): a sun disk like the
// delta light, pi R^2 E; a sky of mean radiance L, pi R^2 pi L; a two-sided triangle twice its one
// side's pi A Le.
TEST(LightSampler, PicksSunSkyAndTwoSidedEmittersByPower) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));  // R = 50 sqrt 2
    Material glow;
    glow.emission = Rgb(1.0f);
    glow.two_sided_emission = true;
    scene.materials.push_back(glow);
    TriangleMesh triangle;  // area 1/2, facing +y, under the sun and the sky's zenith
    triangle.material = 1;
    triangle.positions = {{0, 1, 0}, {0, 1, 1}, {1, 1, 0}};
    triangle.triangles = {{0, 1, 2}};
    scene.meshes.push_back(triangle);
    scene.directional_lights.push_back({Vec3d(0, -1, 0), Rgb(1e-3f), kSunDiameter});
    scene.environment = EnvironmentLight{Rgb(2e-4f), nullptr, 0};
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es, LightStrategy::kPower);
    const double r2 = 2 * 50 * 50;
    const double w_triangle = 2 * kPi * 0.5 * 1, w_sun = kPi * r2 * 1e-3,
                 w_sky = kPi * r2 * kPi * 2e-4;
    const double total = w_triangle + w_sun + w_sky;
    const double alpha = kSunDiameter / 2;
    const double sun_cone = 2 * kPi * (1 - std::cos(alpha));
    // From a point between the triangle and the plane: the triangle's back faces it.
    const Vec3 ref = Vec3(Vec3d(0.25, 0.5, 0.25) - (*es)->origin());
    int seen[3] = {};
    constexpr int kN = 3000;
    for (int i = 0; i < kN; ++i) {
        const auto ls = sampler.Sample(ref, Vec3(0, 1, 0), (i + 0.5f) / kN, {0.3f, 0.6f}, 0);
        if (!ls) continue;  // the sky below the horizon is not refused: it is all directions
        EXPECT_FALSE(ls->delta);
        if (ls->radiance == Rgb(1.0f)) {  // the triangle, from behind
            ++seen[0];
            const float dist2 = LengthSquared(ls->point.p - ref);
            const float cos_light = std::abs(ls->wi.y);
            EXPECT_NEAR(ls->pdf, w_triangle / total * dist2 / (cos_light * 0.5), 1e-4 * ls->pdf);
        } else if (ls->radiance == Rgb(2e-4f)) {
            ++seen[2];
            EXPECT_NEAR(ls->pdf, w_sky / total / (4 * kPi), 1e-4 * ls->pdf);
        } else {
            ++seen[1];
            EXPECT_NEAR(ls->pdf, w_sun / total / sun_cone, 2e-3 * ls->pdf);
            EXPECT_NEAR(ls->radiance.g, 1e-3 / (kPi * std::sin(alpha) * std::sin(alpha)),
                        1e-4 * ls->radiance.g);
        }
    }
    EXPECT_NEAR(seen[0], kN * w_triangle / total, 2);
    EXPECT_NEAR(seen[1], kN * w_sun / total, 2);
    EXPECT_NEAR(seen[2], kN * w_sky / total, 2);
}

}  // namespace
}  // namespace lf
