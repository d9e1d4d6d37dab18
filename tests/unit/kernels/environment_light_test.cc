// The environment light against closed forms: a uniform sky and a half-lit map over an open
// Lambertian plane, a sun-in-sky map whose irradiance is a sum over its texels, a single bright
// column that must light from where rotate_y turns it, a texel that must light where Blender shows
// it; and the map sampler's directions against its own density by chi-square.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <utility>

#include "chi_square.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/environment_emitter.h"
#include "lf/kernels/path_tracer.h"
#include "plane_render.h"
#include "point_estimate.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kSigmas = 5;

// A linear HDR map of w x h texels.
std::shared_ptr<const TextureImage> Map(int w, int h, const std::function<float(int, int)>& f) {
    auto map = std::make_shared<TextureImage>();
    map->name = "test.hdr";
    map->width = w;
    map->height = h;
    map->channels = 3;
    map->hdr = true;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) map->texels32.push_back(f(x, y));
        }
    }
    return map;
}

// A sun in a sky: rows above the horizon 0.2, below 0.02, one texel (40, 8) of 2000.
std::shared_ptr<const TextureImage> SunInSky() {
    return Map(64, 32, [](int x, int y) {
        return x == 40 && y == 8 ? 2000.0f : y < 16 ? 0.2f : 0.02f;
    });
}

// The irradiance on an upward surface, E = integral of Le max(0, cos theta): a texel of row y
// spans theta in [pi y / h, pi (y + 1) / h] and 2 pi / w of azimuth, and there
// integral of cos(theta) sin(theta) dtheta = (sin^2 theta1 - sin^2 theta0) / 2.
double UpwardIrradiance(const TextureImage& map, float scale) {
    double e = 0;
    for (int y = 0; y < map.height / 2; ++y) {
        const double s0 = std::sin(kPi * y / map.height), s1 = std::sin(kPi * (y + 1) / map.height);
        for (int x = 0; x < map.width; ++x) {
            const double texel = map.texels32[size_t(y * map.width + x) * 3];
            e += texel * scale * (2 * kPi / map.width) * (s1 * s1 - s0 * s0) / 2;
        }
    }
    return e;
}

struct Traced {
    std::unique_ptr<EmbreeScene> embree;
    std::unique_ptr<PathTracer> tracer;
};

Traced Trace(const Scene& scene) {
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    Traced t{std::move(*es), nullptr};
    t.tracer = std::make_unique<PathTracer>(*t.embree, -1);
    return t;
}

// A plane point seen from the camera above PlaneUnderCamera's plane.
testing::PointEstimate PlanePoint(const Traced& t, int n) {
    return testing::EstimateRadiance(
        *t.tracer, testing::RayBetween(Vec3d(0, 3, 0), Vec3d(0.3, 0, -0.2), t.embree->origin()), n);
}

// Radiance L from every direction onto an open plane: rho / pi * pi L = rho L. A camera ray that
// misses everything sees L itself.
TEST(EnvironmentLight, UniformSkyOverOpenPlaneRendersRhoL) {
    const Rgb rho(0.5f, 0.25f, 0.75f), sky(0.5f, 1.0f, 2.0f);
    Scene scene = testing::PlaneUnderCamera(rho);
    scene.environment = EnvironmentLight{sky, nullptr, 0};
    const Traced t = Trace(scene);
    testing::ExpectEstimateNear(PlanePoint(t, 4000), rho * sky);
    const testing::PointEstimate up = testing::EstimateRadiance(
        *t.tracer, testing::RayBetween(Vec3d(0, 3, 0), Vec3d(0.2, 4, 0.1), t.embree->origin()), 4);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(up.mean[c], sky[c]);
}

// A map lit (1) above the horizon and black below, under an upward plane: the plane sees a
// uniform hemisphere, rho / pi * pi * radiance, whatever the rotation.
TEST(EnvironmentLight, HalfLitMapOverUpwardPlaneRendersRho) {
    const Rgb rho(0.5f, 0.25f, 0.75f), scale(2.0f, 1.0f, 0.5f);
    Scene scene = testing::PlaneUnderCamera(rho);
    scene.environment =
        EnvironmentLight{scale, Map(16, 8, [](int, int y) { return y < 4 ? 1.0f : 0.0f; }), 0.7};
    testing::ExpectEstimateNear(PlanePoint(Trace(scene), 4000), rho * scale);
}

// An 8-bit map holds sRGB-encoded colour: texel 128 is 0.2158605 linear, times `radiance`.
TEST(EnvironmentLight, EightBitMapIsDecodedFromSrgb) {
    auto map = std::make_shared<TextureImage>();
    map->name = "sky.png";
    map->width = 2;
    map->height = 1;
    map->channels = 3;
    map->texels8 = {255, 255, 255, 128, 64, 0};  // u < 1/2: white; u > 1/2: (128, 64, 0)
    const EnvironmentEmitter sky(EnvironmentLight{Rgb(2.0f), map, 0});
    // u = 0.5 + atan2(z, x) / (2 pi): z < 0 reads the left half, z > 0 the right.
    EXPECT_EQ(sky.Le(Vec3(0, 0, -1)), Rgb(2.0f));
    const Rgb right = sky.Le(Vec3(0, 0, 1));
    EXPECT_NEAR(right.r, 2 * 0.2158605f, 1e-6f);
    EXPECT_NEAR(right.g, 2 * 0.0512695f, 1e-6f);
    EXPECT_EQ(right.b, 0);
}

// Negative, infinite and NaN texels (HDR files can hold them) emit nothing and are never drawn.
TEST(EnvironmentLight, NonFiniteTexelsEmitNothing) {
    const float bad[] = {-1.0f, INFINITY, NAN};
    const EnvironmentEmitter sky(EnvironmentLight{
        Rgb(1.0f), Map(4, 1, [&](int x, int) { return x < 3 ? bad[x] : 2.0f; }), 0});
    for (int i = 0; i < 1000; ++i) {
        Sampler sampler(3, 0, 0, uint64_t(i));
        const auto ds = sky.Sample(sampler.Get2D());
        ASSERT_TRUE(ds);
        ASSERT_EQ(ds->radiance, Rgb(2.0f));
        ASSERT_GT(ds->wi.z, 0);  // u in [3/4, 1): atan2(z, x) in [pi/2, pi)
        ASSERT_LT(ds->wi.x, 0);
    }
    // u = 0.125, 0.375 and 0.625: atan2(z, x) = -3 pi / 4, -pi / 4, pi / 4.
    for (const Vec3& w : {Vec3(-1, 0, -1), Vec3(1, 0, -1), Vec3(1, 0, 1)}) {
        EXPECT_EQ(sky.Le(Normalize(w)), Rgb(0.0f));
        EXPECT_EQ(sky.Pdf(Normalize(w)), 0);
    }
    EXPECT_TRUE(std::isfinite(sky.MeanRadiance().g));
}

// A small bright sun in a dim sky: the plane's radiance is rho / pi times the texel sum E, and
// importance sampling (with MIS against the BSDF) gets there.
TEST(EnvironmentLight, SunInSkyMapRendersItsTexelSum) {
    const Rgb rho(0.5f);
    Scene scene = testing::PlaneUnderCamera(rho);
    scene.environment = EnvironmentLight{Rgb(1.0f), SunInSky(), 0};
    const double e = UpwardIrradiance(*scene.environment->map, 1);
    const testing::PointEstimate got = PlanePoint(Trace(scene), 4000);
    testing::ExpectEstimateNear(got, rho * float(e / kPi));
    std::printf("[env] path tracer, 4000 samples: relative standard error %.4f\n",
                got.standard_error[1] / got.mean[1]);
}

// Irradiance on an upward surface from the sun-in-sky map, two unbiased estimators at equal
// sample counts: the emitter's importance sampling, and uniform directions on the sphere. Both
// agree with the texel sum; importance sampling's error is far smaller.
TEST(EnvironmentLight, ImportanceSamplingIsUnbiasedWithLowerVariance) {
    const EnvironmentEmitter sky(EnvironmentLight{Rgb(1.0f), SunInSky(), 0});
    const double e = UpwardIrradiance(*SunInSky(), 1);
    constexpr int kN = 20000;
    double sum[2] = {}, sum2[2] = {};
    for (int i = 0; i < kN; ++i) {
        Sampler sampler(7, 0, 0, uint64_t(i));
        const Vec2 u = sampler.Get2D();
        double value[2] = {0, 0};
        if (const auto ds = sky.Sample(u)) {
            EXPECT_NEAR(ds->pdf, sky.Pdf(ds->wi), 1e-3 * ds->pdf);
            value[0] = ds->radiance.g * std::max(0.0f, ds->wi.y) / ds->pdf;
        }
        const float z = 1 - 2 * u.x, r = std::sqrt(std::max(0.0f, 1 - z * z));
        const Vec3 w(r * std::cos(2 * float(kPi) * u.y), z, r * std::sin(2 * float(kPi) * u.y));
        value[1] = sky.Le(w).g * std::max(0.0f, w.y) * 4 * kPi;
        for (int k = 0; k < 2; ++k) {
            sum[k] += value[k];
            sum2[k] += value[k] * value[k];
        }
    }
    double sd[2];
    for (int k = 0; k < 2; ++k) {
        const double mean = sum[k] / kN;
        sd[k] = std::sqrt((sum2[k] - sum[k] * mean) / (kN - 1));
        EXPECT_NEAR(mean, e, kSigmas * sd[k] / std::sqrt(double(kN)))
            << (k ? "uniform" : "importance");
    }
    std::printf("[env] irradiance %.4f, %d samples: relative error importance %.5f, uniform %.5f\n",
                e, kN, sd[0] / std::sqrt(double(kN)) / e, sd[1] / std::sqrt(double(kN)) / e);
    EXPECT_LT(sd[0], 0.1 * sd[1]);
}

// Chi-square of the sampled directions against Pdf integrated over cells that are the map's
// texels (turned by rotate_y; a quarter turn moves whole columns), on a map with a bright texel,
// a black region and a smooth gradient.
TEST(EnvironmentLight, MapSamplingMatchesItsPdf) {
    constexpr int kW = 16, kH = 8;
    const auto map = Map(kW, kH, [](int x, int y) {
        if (x == 3 && y == 2) return 40.0f;
        if (x >= 10 && x < 13) return 0.0f;
        return 0.1f + 0.05f * float(x) + 0.3f * float(y);
    });
    for (const double rotation : {0.0, kPi / 2}) {
        const EnvironmentEmitter sky(EnvironmentLight{Rgb(1.0f, 0.5f, 0.25f), map, rotation});
        std::vector<double> observed(kW * kH, 0.0), expected(kW * kH, 0.0);
        constexpr int kSamples = 1'000'000;
        for (int i = 0; i < kSamples; ++i) {
            Sampler sampler(11, 0, 0, uint64_t(i));
            const auto ds = sky.Sample(sampler.Get2D());
            ASSERT_TRUE(ds);
            const double v = std::acos(std::clamp(double(ds->wi.y), -1.0, 1.0)) / kPi;
            const double u = 0.5 + std::atan2(double(ds->wi.z), double(ds->wi.x)) / (2 * kPi);
            const int row = std::clamp(int(v * kH), 0, kH - 1);
            const int column = std::clamp(int(u * kW), 0, kW - 1);
            ++observed[size_t(row * kW + column)];
        }
        // The quadrature's pole is +z and its azimuth phi; the map's pole is +y and its
        // u = 0.5 + atan2(z, x) / (2 pi). World (-d.x, d.z, -d.y) has y = cos(theta) and
        // atan2(z, x) = phi - pi: cell (theta, phi) is the map's (v, u) = (theta, phi) / pi, 2 pi.
        double integral = 0;
        for (int row = 0; row < kH; ++row) {
            for (int column = 0; column < kW; ++column) {
                const double p = testing::IntegrateSolidAngle(
                    [&](const Vec3& d) { return double(sky.Pdf(Vec3(-d.x, d.z, -d.y))); },
                    row * kPi / kH, (row + 1) * kPi / kH, column * 2 * kPi / kW,
                    (column + 1) * 2 * kPi / kW, 2, 1e-7);
                expected[size_t(row * kW + column)] = p * kSamples;
                integral += p;
            }
        }
        EXPECT_NEAR(integral, 1, 1e-4);
        const double level = 1 - std::pow(1 - testing::kSignificance, 1.0 / 2);
        EXPECT_GT(testing::ChiSquareFit(observed, expected), level) << "rotate_y " << rotation;
    }
}

// One bright column of texels (u in [5/32, 6/32]), turned by rotate_y = 2: the map's azimuth
// phi = 2 pi (u - 0.5) = atan2(z, x) of the direction after the turn by +rotate_y, so the column
// lies at world azimuth atan2(z, x) = phi + rotate_y (clockwise seen from above). A vertical
// plane facing that azimuth psi receives E = L integral of sin^2(theta) dtheta (= pi / 2) times
// integral of cos(phi - psi) dphi over the column (= 2 sin(dphi / 2)); one facing away, or
// facing where the opposite turn would put the column, receives nothing.
TEST(EnvironmentLight, RotateYTurnsTheSkyClockwiseSeenFromAbove) {
    constexpr int kW = 32, kH = 16, kColumn = 5;
    const double rotate = 2.0;
    const double phi = 2 * kPi * ((kColumn + 0.5) / kW - 0.5);
    const double dphi = 2 * kPi / kW;
    const Rgb rho(0.5f);
    for (const auto& [psi, irradiance] :
         {std::pair{phi + rotate, kPi / 2 * 2 * std::sin(dphi / 2)},
          std::pair{phi + rotate + kPi, 0.0}, std::pair{phi - rotate, 0.0}}) {
        const Vec3d n(std::cos(psi), 0, std::sin(psi));   // atan2(n.z, n.x) = psi
        const Vec3d t(std::sin(psi), 0, -std::cos(psi));  // horizontal, along the plane
        Scene scene;
        Material plane;
        plane.reflectance = rho;
        scene.materials.push_back(plane);
        TriangleMesh quad;
        const Vec3d up(0, 1, 0);
        quad.positions = {-t - up, t - up, t + up, -t + up};
        // Front face (v1 - v0) x (v2 - v0) = 2t x (t + up) = 2 t x up along n.
        quad.triangles = {{0, 1, 2}, {0, 2, 3}};
        ASSERT_NEAR(Dot(Cross(t, up), n), 1, 1e-12);
        scene.meshes.push_back(quad);
        scene.environment = EnvironmentLight{
            Rgb(1.0f), Map(kW, kH, [](int x, int) { return x == kColumn ? 1.0f : 0.0f; }), rotate};
        const Traced tr = Trace(scene);
        const testing::PointEstimate got = testing::EstimateRadiance(
            *tr.tracer, testing::RayBetween(n * 2.0 + up * 0.1, up * 0.1, tr.embree->origin()),
            4000);
        testing::ExpectEstimateNear(got, rho * float(irradiance / kPi));
        if (irradiance == 0) {
            EXPECT_EQ(got.mean[1], 0) << "psi " << psi;
        }
        // Looking out along psi from in front of the plane: the column itself when psi is its
        // azimuth.
        const testing::PointEstimate sky = testing::EstimateRadiance(
            *tr.tracer, testing::RayBetween(n * 2.0, n * 3.0, tr.embree->origin()), 1);
        EXPECT_EQ(sky.mean[1], irradiance > 0 ? 1 : 0) << "psi " << psi;
    }
}

// Where Blender shows a texel of a lat-long map, worked out from Cycles: its world shader's
// Environment Texture (equirectangular) reads direction D (Blender's frame, +z up) at
//   u = (atan2(D.y, D.x) - pi) / (-2 pi),   v = (acos(D.z) - pi) / (-pi)
// (direction_to_equirectangular: range (-2 pi, pi, -pi, pi)), v = 0 the image's bottom row
// (Blender stores images bottom-up). A Mapping node of type Point (its default) rotating about Z
// by alpha between Texture Coordinate and the texture reads D = Rz(alpha) d for ray direction d.
// glTF's frame is Blender's turned: glTF (x, y, z) = Blender (x, z, -y). So for a glTF
// direction g: d = (g.x, -g.z, g.y). Returns the texel (column, row from the top) Blender reads.
std::pair<int, int> BlenderTexel(const Vec3& g, double alpha, int w, int h) {
    const double dx = g.x, dy = -double(g.z), dz = g.y;
    const double x = std::cos(alpha) * dx - std::sin(alpha) * dy;  // Rz(alpha) d
    const double y = std::sin(alpha) * dx + std::cos(alpha) * dy;
    const double u = (std::atan2(y, x) - kPi) / (-2 * kPi);
    const double v = (std::acos(std::clamp(dz, -1.0, 1.0)) - kPi) / -kPi;
    const int column = std::clamp(int(u * w), 0, w - 1);
    const int row_from_bottom = std::clamp(int(v * h), 0, h - 1);
    return {column, h - 1 - row_from_bottom};
}

// One bright texel (column 12, row 2 of 16 x 8) must light exactly the directions where Blender
// shows it (BlenderTexel), with rotate_y_deg playing the Mapping node's Z rotation, and the
// sampler must draw only those directions. Before, the map's centre looked down -z (Blender's +y,
// a quarter turn off) and rotate_y turned the other way.
TEST(EnvironmentLight, BrightTexelLightsWhereBlenderShowsIt) {
    constexpr int kW = 16, kH = 8, kX = 12, kY = 2;
    const auto map = Map(kW, kH, [](int x, int y) { return x == kX && y == kY ? 100.0f : 0.0f; });
    for (const double alpha : {0.0, kPi / 2, 0.5}) {
        const EnvironmentEmitter sky(EnvironmentLight{Rgb(1.0f), map, alpha});
        int lit = 0;
        for (int i = 0; i < 20000; ++i) {
            Sampler sampler(5, 0, 0, uint64_t(i));
            const Vec2 r = sampler.Get2D();
            const float z = 1 - 2 * r.x, s = std::sqrt(std::max(0.0f, 1 - z * z));
            const float phi = 2 * float(kPi) * r.y;
            const Vec3 g(s * std::cos(phi), z, s * std::sin(phi));
            const bool blender_lit = BlenderTexel(g, alpha, kW, kH) == std::pair{kX, kY};
            // Texel borders are measure zero; a float direction within 1e-4 of one may round
            // either way.
            const auto [bx, by] = BlenderTexel(g, alpha + 1e-4, kW, kH);
            const auto [cx, cy] = BlenderTexel(g, alpha - 1e-4, kW, kH);
            if ((bx == kX && by == kY) != (cx == kX && cy == kY)) continue;
            lit += blender_lit;
            ASSERT_EQ(sky.Le(g).g, blender_lit ? 100.0f : 0.0f)
                << "rotate_y " << alpha << " direction " << g.x << " " << g.y << " " << g.z;
        }
        EXPECT_GT(lit, 0);
        for (int i = 0; i < 2000; ++i) {
            Sampler sampler(6, 0, 0, uint64_t(i));
            const auto ds = sky.Sample(sampler.Get2D());
            ASSERT_TRUE(ds);
            EXPECT_EQ(BlenderTexel(ds->wi, alpha, kW, kH), (std::pair{kX, kY}))
                << "rotate_y " << alpha;
        }
    }
}

}  // namespace
}  // namespace lf
