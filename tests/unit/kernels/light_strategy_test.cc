// The light BVH strategy (LightStrategy::kBvh: BVH picks, spherical triangles, sphere cones)
// against the power strategy it replaces: Sample's pdf is Pdf's for the same hit (so MIS stays
// exact), both estimate the same direct light, and the new one with less variance where it
// should have it: a large emitter close by, many emitters at different distances.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/path_tracer.h"
#include "plane_render.h"
#include "point_estimate.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// A one-sided emitting triangle of radiance le facing -y (down, towards the plane).
void AddDownwardTriangle(Scene& scene, int material, const Vec3d& a, const Vec3d& b,
                         const Vec3d& c) {
    TriangleMesh mesh;
    mesh.material = material;
    mesh.positions = {a, b, c};
    // Wound so that the normal (b - a) x (c - a) points down.
    if (Cross(b - a, c - a).y > 0) mesh.positions = {a, c, b};
    mesh.triangles = {{0, 1, 2}};
    scene.meshes.push_back(mesh);
}

int AddEmitter(Scene& scene, const Rgb& le, bool two_sided = false) {
    Material m;
    m.reflectance = Rgb(0.0f);
    m.emission = le;
    m.two_sided_emission = two_sided;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

// A square of half-size a at height h, facing down.
void AddDownwardSquare(Scene& scene, int material, double a, double h) {
    AddDownwardTriangle(scene, material, {-a, h, -a}, {a, h, -a}, {a, h, a});
    AddDownwardTriangle(scene, material, {-a, h, -a}, {a, h, a}, {-a, h, a});
}

// The same square as one mesh of two triangles sharing a diagonal, as a quad shape loads: one
// rectangle light.
void AddDownwardRectangle(Scene& scene, int material, double a, double h) {
    TriangleMesh mesh;
    mesh.material = material;
    mesh.positions = {{-a, h, -a}, {a, h, -a}, {a, h, a}, {-a, h, a}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(mesh);
}

// Which emitter a hit is on: a sphere's index + 1000, or the mesh.
int EmitterId(const SurfaceHit& hit) { return hit.sphere >= 0 ? 1000 + hit.sphere : hit.mesh; }

// For every light sample from ref whose ray reaches the sampled point first, Pdf of that hit is
// the sample's pdf. Returns how many samples were checked per emitter.
std::map<int, int> ExpectPdfMatchesSample(const EmbreeScene& es, const LightSampler& sampler,
                                          const Vec3& ref, const Vec3& n) {
    std::map<int, int> checked;
    constexpr int kGrid = 12, kPicks = 64;
    for (int k = 0; k < kPicks; ++k) {
        for (int i = 0; i < kGrid; ++i) {
            for (int j = 0; j < kGrid; ++j) {
                const float u_pick = (k + 0.5f) / kPicks;
                const Vec2 u((i + 0.37f) / kGrid, (j + 0.71f) / kGrid);
                const std::optional<LightSample> ls = sampler.Sample(ref, n, u_pick, u, 0);
                if (!ls || ls->delta) continue;
                const std::optional<SurfaceHit> hit = es.Intersect(Ray{ref, ls->wi});
                if (!hit) continue;
                const float dist = Length(ls->point.p - ref);
                if (Length(hit->p - ls->point.p) > 1e-3f * dist) continue;  // occluded
                const float pdf = sampler.Pdf(ref, n, *hit);
                EXPECT_NEAR(pdf, ls->pdf, 2e-3f * ls->pdf)
                    << "emitter " << EmitterId(*hit) << " u " << u.x << "," << u.y;
                ++checked[EmitterId(*hit)];
            }
        }
    }
    return checked;
}

// A large square close to the reference point (solid-angle sampled, cosine-warped), a small
// triangle far away (area sampled), a two-sided sphere seen from outside and from inside.
TEST(LightStrategy, PdfMatchesSampleNearFarInsideAndOutside) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    const int panel = AddEmitter(scene, Rgb(1.0f, 2.0f, 3.0f));
    const int glow = AddEmitter(scene, Rgb(5.0f), true);
    // So bright that the BVH picks it about as often as the others from the point below.
    const int beacon = AddEmitter(scene, Rgb(1e5f));
    AddDownwardSquare(scene, panel, 1.0, 1.0);                                      // meshes 1, 2
    AddDownwardTriangle(scene, beacon, {-15, 5, 0}, {-14.9, 5, 0}, {-15, 5, 0.1});  // mesh 3
    scene.spheres.push_back({"ball", glow, Vec3d(3, 1, 0), 0.5});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const LightSampler sampler(**es);
    ASSERT_EQ(sampler.strategy(), LightStrategy::kBvh);
    const Vec3d& origin = (*es)->origin();

    const Vec3 below(Vec3d(0.2, 0.5, 0.1) - origin);
    const std::map<int, int> outside = ExpectPdfMatchesSample(**es, sampler, below, {0, 1, 0});
    for (int id : {1, 2, 3, 1000}) EXPECT_GT(outside.count(id) ? outside.at(id) : 0, 5) << id;

    const Vec3 in_ball(Vec3d(3.1, 1.2, 0.05) - origin);
    const std::map<int, int> inside = ExpectPdfMatchesSample(**es, sampler, in_ball, {0, 1, 0});
    EXPECT_GT(inside.count(1000) ? inside.at(1000) : 0, 100);

    // In a volume (no normal) the square's triangles are sampled uniformly in solid angle: a
    // constant pdf per triangle.
    std::optional<float> first;
    for (int i = 0; i < 64; ++i) {
        const auto ls =
            sampler.Sample(below, Vec3(0, 0, 0), (i + 0.5f) / 64, {(i % 8 + 0.5f) / 8, 0.3f}, 0);
        if (!ls) continue;
        const auto hit = (*es)->Intersect(Ray{below, ls->wi});
        ASSERT_TRUE(hit);
        if (hit->mesh != 1) continue;
        if (!first) first = ls->pdf;
        EXPECT_FLOAT_EQ(ls->pdf, *first);
    }
    EXPECT_TRUE(first);
    const std::map<int, int> volume = ExpectPdfMatchesSample(**es, sampler, below, Vec3(0, 0, 0));
    EXPECT_GT(volume.count(1) ? volume.at(1) : 0, 5);
}

// Direct light (one bounce) at `x` on the plane, seen from above, by both strategies.
struct StrategyEstimates {
    testing::PointEstimate power, bvh;
};
StrategyEstimates EstimateBoth(const Scene& scene, const Vec3d& x, int n) {
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok());
    const Ray ray = testing::RayBetween(x + Vec3d(0.05, 0.1, 0.02), x, (*es)->origin());
    return {testing::EstimateRadiance(PathTracer(**es, 1, LightStrategy::kPower), ray, n),
            testing::EstimateRadiance(PathTracer(**es, 1, LightStrategy::kBvh), ray, n)};
}

// Same mean within k standard errors of the difference, per channel.
void ExpectSameMean(const StrategyEstimates& e, double k = 5) {
    for (int c = 0; c < 3; ++c) {
        const double se = std::hypot(e.power.standard_error[c], e.bvh.standard_error[c]);
        EXPECT_NEAR(e.bvh.mean[c], e.power.mean[c], k * se) << "channel " << c;
    }
}

// The variance of one sample of the BVH strategy at most `ratio` times the power strategy's.
void ExpectLessVariance(const StrategyEstimates& e, double ratio) {
    for (int c = 0; c < 3; ++c) {
        EXPECT_LT(e.bvh.sample_sd[c] * e.bvh.sample_sd[c],
                  ratio * e.power.sample_sd[c] * e.power.sample_sd[c])
            << "channel " << c;
    }
}

// Under the centre of a downward square of side a at height h over a plane of albedo rho, both
// strategies estimate rho Le F (F the view factor of the square from the point under its
// centre), the BVH with at most half the variance.
void ExpectUnderSquareBothRightLessVariance(const Scene& scene, const Rgb& rho, const Rgb& le,
                                            double a, double h) {
    const StrategyEstimates e = EstimateBoth(scene, {0, 0, 0}, 20000);
    ExpectSameMean(e);
    const double x = a / h, sx = std::sqrt(1 + x * x);
    const double f = 4 * (2 * x / sx * std::atan(x / sx)) / (2 * kPi);
    testing::ExpectEstimateNear(e.bvh, rho * le * float(f));
    testing::ExpectEstimateNear(e.power, rho * le * float(f));
    ExpectLessVariance(e, 0.5);
}

// A 4 x 4 emitter 0.3 above the point: from there it covers most of the hemisphere, and area
// sampling's 1 / r^2 and cosines make most of its variance. (The cosine warp does nothing here:
// the triangles' corners all lie at the same grazing angle.) Both agree with the closed form
// rho Le F (F the view factor of the square from the point under its centre).
TEST(LightStrategy, LargeNearbyEmitterSameMeanLessVariance) {
    const Rgb rho(0.5f), le(1.0f, 2.0f, 3.0f);
    const double a = 2, h = 0.3;
    Scene scene = testing::PlaneUnderCamera(rho);
    AddDownwardSquare(scene, AddEmitter(scene, le), a, h);
    ExpectUnderSquareBothRightLessVariance(scene, rho, le, a, h);
}

// The same as one rectangle light (spherical rectangle sampling): the same mean, less variance;
// and Pdf agrees with Sample on it from near (by solid angle) and far (by area), with and
// without a normal.
TEST(LightStrategy, RectangleLightSameMeanLessVarianceAndPdfMatchesSample) {
    const Rgb rho(0.5f), le(1.0f, 2.0f, 3.0f);
    const double a = 2, h = 0.3;
    Scene scene = testing::PlaneUnderCamera(rho);
    AddDownwardRectangle(scene, AddEmitter(scene, le), a, h);
    {
        auto es = EmbreeScene::Build(scene);
        ASSERT_TRUE(es.ok());
        const LightSampler sampler(**es);
        EXPECT_EQ(sampler.size(), 1u);  // one light, not two triangles
        const Vec3d& origin = (*es)->origin();
        for (const Vec3d& at : {Vec3d(0.2, 0.1, 0.1), Vec3d(1.9, 0.25, -1.5), Vec3d(5, 0.2, 4)}) {
            for (const Vec3& n : {Vec3(0, 1, 0), Vec3(0.6f, 0.8f, 0), Vec3(0, 0, 0)}) {
                const std::map<int, int> checked =
                    ExpectPdfMatchesSample(**es, sampler, Vec3(at - origin), n);
                EXPECT_GT(checked.count(1) ? checked.at(1) : 0, 100) << at.x << " " << at.y;
            }
        }
    }
    ExpectUnderSquareBothRightLessVariance(scene, rho, le, a, h);
}

// 300 small emitters (triangles 0.1 across) at distances from 1 to 30 (few enough close by not
// to hide each other), all of one radiance: picking by power spends most samples on lights too
// far to matter, the BVH on the few close ones.
TEST(LightStrategy, ManyEmittersAtDifferentDistancesSameMeanLessVariance) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    const int material = AddEmitter(scene, Rgb(20.0f, 10.0f, 5.0f));
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int i = 0; i < 300; ++i) {
        const double distance = std::pow(30.0, unit(rng));  // 1 .. 30, log-uniform
        const double phi = 2 * kPi * unit(rng), cos_t = 0.2 + 0.8 * unit(rng);
        const double sin_t = std::sqrt(1 - cos_t * cos_t);
        const Vec3d c(distance * sin_t * std::cos(phi), distance * cos_t,
                      distance * sin_t * std::sin(phi));
        AddDownwardTriangle(scene, material, c, c + Vec3d(0.1, 0, 0), c + Vec3d(0, 0, 0.1));
    }
    const StrategyEstimates e = EstimateBoth(scene, {0, 0, 0}, 20000);
    ExpectSameMean(e);
    ExpectLessVariance(e, 0.5);
}

// Point and spot lights go through the BVH too, the directional light beside it with its power
// share: both strategies light the plane alike.
TEST(LightStrategy, DeltaLightsSameMean) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    scene.point_lights.push_back({Vec3d(0.5, 1, 0), Rgb(1.0f, 2.0f, 3.0f)});
    SpotLight spot;
    spot.position = Vec3d(-1, 2, 0.5);
    spot.direction = Vec3d(0.3, -1, 0);
    spot.intensity = Rgb(5.0f);
    spot.inner_cone = 0.3;
    spot.outer_cone = 0.6;
    scene.spot_lights.push_back(spot);
    scene.directional_lights.push_back({Vec3d(0.2, -1, 0.1), Rgb(0.3f)});
    AddDownwardSquare(scene, AddEmitter(scene, Rgb(2.0f)), 0.2, 1.5);
    ExpectSameMean(EstimateBoth(scene, {-0.3, 0, 0.2}, 20000));
}

}  // namespace
}  // namespace lf
