// SceneMedia: transmittance by ratio tracking and free paths by delta tracking on SampleTMaj
// against Beer's law and quadrature, the majorant grid as a bound, rays that miss or start inside
// a grid, and emission (black-body temperature grids in absolute units).
#include "lf/kernels/media.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "lf/core/blackbody.h"
#include "lf/core/medium.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

// Render space is world minus this: the grids' maps must add it back.
const Vec3d kOrigin(100, -50, 20);
constexpr int kRuns = 200'000;

// A grid's index-to-world map: translation * rotation * uniform scale.
struct Placement {
    Vec3d translation;
    Vec3d axis;    // of the rotation, unit
    double angle;  // radians
    double scale;
};

const Placement kTilted{{100.3, -49.2, 20.6}, Normalize(Vec3d(1, 1, 1)), 0.7, 0.1};

std::shared_ptr<VolumeGrid> MakeGrid(int n, const std::function<float(int, int, int)>& value,
                                     const Placement& at, float background = 0) {
    auto grid = std::make_shared<VolumeGrid>();
    grid->name = "test.vdb#density";
    grid->min = {-3, 2, 5};
    grid->size = {n, n, n};
    grid->background = background;
    for (int z = 0; z < n; ++z) {
        for (int y = 0; y < n; ++y) {
            for (int x = 0; x < n; ++x) grid->values.push_back(value(x, y, z));
        }
    }
    const double s = std::sin(at.angle / 2), c = std::cos(at.angle / 2);
    const Vec3d no_move(0, 0, 0), unit(1, 1, 1);
    const std::array<double, 4> identity{0, 0, 0, 1};
    grid->index_to_world = Affine::FromTrs(
        at.translation, {at.axis.x * s, at.axis.y * s, at.axis.z * s, c}, unit * at.scale);
    grid->world_to_index =
        Affine::FromTrs(-at.translation, identity, unit)
            .Then(
                Affine::FromTrs(no_move, {-at.axis.x * s, -at.axis.y * s, -at.axis.z * s, c}, unit))
            .Then(Affine::FromTrs(no_move, identity, unit / at.scale));
    return grid;
}

// World position of a point given relative to the grid's first lattice point, in index units.
Vec3d World(const VolumeGrid& grid, const Vec3d& relative) {
    return grid.index_to_world.Apply(relative + Vec3d(grid.min[0], grid.min[1], grid.min[2]));
}

Medium GridMedium(std::shared_ptr<const VolumeGrid> density, const Rgb& sigma_a,
                  const Rgb& sigma_s) {
    Medium m;
    m.name = "smoke";
    m.type = Medium::Type::kGrid;
    m.sigma_a = sigma_a;
    m.sigma_s = sigma_s;
    m.density = std::move(density);
    return m;
}

SceneMedia OneMedium(const Medium& m) {
    Scene scene;
    scene.media.push_back(m);
    return SceneMedia(scene, kOrigin);
}

// The render-space ray from world point a towards world point b, d = b - a (not unit): t_max 1
// reaches b.
Ray RayBetween(const Vec3d& a, const Vec3d& b) { return {Vec3(a - kOrigin), Vec3(b - a)}; }

// Ratio tracking (pbrt-v4's TraceTransmittance) with hero channel `hero`: at each collision
// T *= t_maj sigma_n / pdf, pdf = t_maj[hero] sigma_maj[hero]; past the last, t_maj / t_maj[hero].
Rgb RatioTracking(const SceneMedia& media, const Ray& ray, float t_max, int hero, MediumRng& rng) {
    Rgb t(1.0f);
    const Rgb t_maj = media.SampleTMaj(
        0, ray, t_max, hero, rng,
        [&](const Vec3&, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb& t_maj_step) {
            Rgb sigma_n = sigma_maj - mp.sigma_a - mp.sigma_s;
            for (int c = 0; c < 3; ++c) sigma_n[c] = std::max(0.0f, sigma_n[c]);
            t *= t_maj_step * sigma_n / (t_maj_step[hero] * sigma_maj[hero]);
            return !t.IsBlack();
        });
    return t * t_maj / t_maj[hero];
}

// The mean of kRuns ratio-tracking estimates equals `expected` per channel within 4 standard
// errors; the hero channel takes turns.
void ExpectTransmittance(const SceneMedia& media, const Ray& ray, float t_max, const Rgb& expected,
                         const std::string& name) {
    double sum[3] = {}, sum2[3] = {};
    for (int i = 0; i < kRuns; ++i) {
        MediumRng rng(MixBits(std::hash<std::string>{}(name) + uint64_t(i)));
        const Rgb t = RatioTracking(media, ray, t_max, i % 3, rng);
        for (int c = 0; c < 3; ++c) {
            sum[c] += t[c];
            sum2[c] += double(t[c]) * t[c];
        }
    }
    for (int c = 0; c < 3; ++c) {
        const double mean = sum[c] / kRuns;
        const double se = std::sqrt(std::max(0.0, sum2[c] / kRuns - mean * mean) / kRuns);
        EXPECT_NEAR(mean, expected[c], 4 * se + 1e-6) << name << " channel " << c;
        std::printf("[media] %-14s channel %d: %.5f expected %.5f (se %.1e)\n", name.c_str(), c,
                    mean, double(expected[c]), se);
    }
}

Rgb BeerLambert(const Rgb& sigma_t, double optical_length) {
    Rgb t;
    for (int c = 0; c < 3; ++c) t[c] = float(std::exp(-sigma_t[c] * optical_length));
    return t;
}

// Int density along the world segment a -> b by quadrature of VolumeGrid::Lookup, in metres.
double DensityIntegral(const VolumeGrid& grid, const Vec3d& a, const Vec3d& b) {
    const double length = Length(b - a);
    return testing::Integrate1D(
        [&](double t) {
            return double(grid.Lookup(grid.world_to_index.Apply(a + (b - a) * (t / length))));
        },
        0, length, 4000);
}

// Chromatic, with optical depths of 0.2 to 2 on the test rays: the hero channel's estimates of
// the others stay of bounded variance (a deep hero would make their estimates heavy-tailed).
const Rgb kSigmaA(0.2f, 0.4f, 0.7f), kSigmaS(0.1f, 0.2f, 0.3f);

TEST(SceneMedia, HomogeneousChromaticBeerLambert) {
    Medium m;
    m.sigma_a = {0.2f, 0.9f, 2.0f};
    m.sigma_s = {0.5f, 0.3f, 0.1f};
    m.g = 0.4f;
    const SceneMedia media = OneMedium(m);
    EXPECT_FALSE(media.empty());
    EXPECT_FALSE(media.IsHomogeneousAbsorber(0));
    EXPECT_FALSE(media.IsEmissive(0));
    EXPECT_EQ(media.g(0), 0.4f);
    // d of length 2: t_max 0.75 is 1.5 m.
    const Ray ray{{1, 2, 3}, {1.2f, 1.6f, 0}};
    const Rgb expected = BeerLambert(m.sigma_a + m.sigma_s, 1.5);
    ExpectTransmittance(media, ray, 0.75f, expected, "homogeneous");
    const Rgb beer = media.HomogeneousTransmittance(0, 1.5f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(beer[c], expected[c], 1e-6 * expected[c]);

    m.sigma_s = Rgb(0.0f);
    m.sigma_a = {0, 1, 2};
    const SceneMedia absorber = OneMedium(m);
    EXPECT_TRUE(absorber.IsHomogeneousAbsorber(0));
    // No absorption is no attenuation, also over an infinite distance.
    EXPECT_EQ(absorber.HomogeneousTransmittance(0, INFINITY), Rgb(1, 0, 0));
}

TEST(SceneMedia, ConstantGridFromInside) {
    const auto grid = MakeGrid(
        12, [](int, int, int) { return 0.8f; }, kTilted);
    const SceneMedia media = OneMedium(GridMedium(grid, kSigmaA, kSigmaS));
    // Both ends inside the lattice, where the trilinear density is 0.8 throughout.
    const Vec3d a = World(*grid, {2.3, 3.1, 4.7}), b = World(*grid, {9.6, 8.2, 7.1});
    ExpectTransmittance(media, RayBetween(a, b), 1,
                        BeerLambert((kSigmaA + kSigmaS) * 0.8f, Length(b - a)), "constant");
}

TEST(SceneMedia, ConstantEverywhereThroughTheBox) {
    // The background equals the lattice: the medium fills space, before, in and after the box.
    const auto grid = MakeGrid(
        12, [](int, int, int) { return 0.8f; }, kTilted, 0.8f);
    const SceneMedia media = OneMedium(GridMedium(grid, kSigmaA, kSigmaS));
    const Vec3d a = World(*grid, {-6, 5, 3}), b = World(*grid, {19, 7, 9});
    ExpectTransmittance(media, RayBetween(a, b), 1,
                        BeerLambert((kSigmaA + kSigmaS) * 0.8f, Length(b - a)), "background");
}

TEST(SceneMedia, LinearRampAgainstQuadrature) {
    const auto grid = MakeGrid(
        16, [](int x, int, int) { return 0.1f + 1.5f * float(x) / 15; }, kTilted);
    const SceneMedia media = OneMedium(GridMedium(grid, kSigmaA, kSigmaS));
    // From outside the box through it and out: the rim where the lattice fades to 0 included.
    const Vec3d a = World(*grid, {-4, 1.5, 3}), b = World(*grid, {20, 12.5, 9});
    ExpectTransmittance(media, RayBetween(a, b), 1,
                        BeerLambert(kSigmaA + kSigmaS, DensityIntegral(*grid, a, b)), "ramp");
}

TEST(SceneMedia, EmptyVoxelsAddNoBias) {
    // Density 1 but for the slab 10 <= x <= 20 (relative): along x from 2 to 28 the density is
    // 1 for 7 voxels, fades out and in over 1 voxel each, and 1 for 7: 15 voxels of 0.05 m.
    const auto grid = MakeGrid(
        32, [](int x, int, int) { return x >= 10 && x <= 20 ? 0.0f : 1.0f; }, kTilted);
    const SceneMedia media = OneMedium(GridMedium(grid, kSigmaA, kSigmaS));
    const Vec3d a = World(*grid, {2, 15.5, 15.5}), b = World(*grid, {28, 15.5, 15.5});
    ExpectTransmittance(media, RayBetween(a, b), 1, BeerLambert(kSigmaA + kSigmaS, 15 * 0.1),
                        "zero slab");
}

TEST(SceneMedia, DeltaTrackingFreePathIsExponential) {
    // Density 0.5 along the ray (at y = z = 16, the lattice and the background); spikes of 4 at
    // y = 18 share its majorant cells, so most tentative collisions are null.
    const Placement at{{100.3, -49.2, 20.6}, Normalize(Vec3d(1, -2, 0.5)), 1.1, 0.05};
    const auto grid = MakeGrid(
        32, [](int x, int y, int) { return y == 18 && x % 4 == 0 ? 4.0f : 0.5f; }, at, 0.5f);
    const SceneMedia media = OneMedium(GridMedium(grid, Rgb(1.5f), Rgb(0.5f)));
    const Vec3d a = World(*grid, {1, 16, 16}), b = World(*grid, {2, 16, 16});
    const Ray ray = RayBetween(a, b);
    constexpr double kRate = 0.5 * 2;  // per metre
    double sum = 0, sum2 = 0;
    int beyond_one = 0;
    long null_collisions = 0;
    for (int i = 0; i < kRuns; ++i) {
        MediumRng rng(MixBits(uint64_t(i) + 99));
        double distance = -1;
        media.SampleTMaj(
            0, ray, INFINITY, i % 3, rng,
            [&](const Vec3& p, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb&) {
                const float sigma_t = mp.sigma_a[0] + mp.sigma_s[0];
                if (rng.Uniform() < sigma_t / sigma_maj[0]) {
                    distance = Length(Vec3d(p) - Vec3d(ray.o));
                    return false;
                }
                ++null_collisions;
                return true;
            });
        ASSERT_GE(distance, 0);
        sum += distance;
        sum2 += distance * distance;
        beyond_one += distance > 1;
    }
    const double mean = sum / kRuns, se = std::sqrt((sum2 / kRuns - mean * mean) / kRuns);
    EXPECT_NEAR(mean, 1 / kRate, 4 * se);
    const double p = std::exp(-kRate * 1);
    EXPECT_NEAR(double(beyond_one) / kRuns, p, 4 * std::sqrt(p * (1 - p) / kRuns));
    EXPECT_GT(null_collisions, kRuns);
}

TEST(SceneMedia, MajorantBoundsTheDensity) {
    const auto random = [](int x, int y, int z) {
        const uint64_t h =
            MixBits(uint64_t(x) * 73856093u ^ uint64_t(y) * 19349663u ^ uint64_t(z) * 83492791u);
        const float u = float(h >> 40) * 0x1p-24f;
        return u < 0.3f ? 0.0f : u * u * u;
    };
    const auto grid = MakeGrid(20, random, kTilted);
    const SceneMedia media = OneMedium(GridMedium(grid, Rgb(30, 20, 10), Rgb(20, 25, 5)));
    long collisions = 0, violations = 0;
    for (int i = 0; i < 4000; ++i) {
        MediumRng rng{uint64_t(i)};
        // From inside (half the rays) or outside the box, through a point inside it.
        const auto point = [&](double lo, double hi) {
            return Vec3d(lo + (hi - lo) * rng.Uniform(), lo + (hi - lo) * rng.Uniform(),
                         lo + (hi - lo) * rng.Uniform());
        };
        const Vec3d a = World(*grid, i % 2 ? point(-1, 20) : point(-10, 30));
        const Vec3d b = World(*grid, point(0, 19));
        media.SampleTMaj(0, RayBetween(a, b), 3, i % 3, rng,
                         [&](const Vec3&, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb&) {
                             ++collisions;
                             for (int c = 0; c < 3; ++c) {
                                 violations +=
                                     mp.sigma_a[c] + mp.sigma_s[c] > sigma_maj[c] * (1 + 1e-6f);
                             }
                             return true;
                         });
    }
    EXPECT_EQ(violations, 0);
    EXPECT_GT(collisions, 100'000);
}

TEST(SceneMedia, MissesAndStartsInside) {
    const auto grid = MakeGrid(
        8, [](int, int, int) { return 1.0f; }, kTilted);
    const SceneMedia media = OneMedium(GridMedium(grid, Rgb(40.0f), Rgb(10.0f)));
    int calls = 0;
    const auto count = [&](const Vec3&, const MediumPoint&, const Rgb&, const Rgb&) {
        ++calls;
        return true;
    };
    MediumRng rng(5);
    // Passing beside the box, along a lattice axis and obliquely.
    for (const auto& [a, b] : {std::pair{Vec3d(-5, 12, 3), Vec3d(15, 12, 3)},
                               std::pair{Vec3d(-5, -3, 3), Vec3d(15, -2, 9)}}) {
        EXPECT_EQ(media.SampleTMaj(0, RayBetween(World(*grid, a), World(*grid, b)), INFINITY, 0,
                                   rng, count),
                  Rgb(1.0f));
    }
    // Pointing away from it.
    EXPECT_EQ(media.SampleTMaj(0, RayBetween(World(*grid, {-2, 3, 3}), World(*grid, {-3, 3, 3})),
                               INFINITY, 1, rng, count),
              Rgb(1.0f));
    EXPECT_EQ(calls, 0);

    // From inside to infinity: the walk ends, every collision inside the box.
    int outside = 0;
    for (int i = 0; i < 1000; ++i) {
        const Rgb t_maj = media.SampleTMaj(
            0, RayBetween(World(*grid, {3.5, 3.5, 3.5}), World(*grid, {4.1, 3.9, 2.5})), INFINITY,
            i % 3, rng, [&](const Vec3& p, const MediumPoint&, const Rgb&, const Rgb&) {
                ++calls;
                const Vec3d q = grid->world_to_index.Apply(Vec3d(p) + kOrigin) - Vec3d(-3, 2, 5);
                outside += MaxComponent(q) > 8 + 1e-3 || std::min({q.x, q.y, q.z}) < -1 - 1e-3;
                return true;
            });
        EXPECT_TRUE(t_maj.IsFinite() && t_maj.MaxComponent() <= 1 && t_maj.r >= 0);
    }
    EXPECT_EQ(outside, 0);
    EXPECT_GT(calls, 1000);
}

// Le at each collision from the callback, against Le computed from the grids themselves.
void ExpectEmission(const SceneMedia& media, const Ray& ray,
                    const std::function<Rgb(const Vec3d&)>& expected, double tolerance) {
    MediumRng rng(3);
    int calls = 0;
    media.SampleTMaj(0, ray, 1, 0, rng,
                     [&](const Vec3& p, const MediumPoint& mp, const Rgb&, const Rgb&) {
                         const Rgb want = expected(Vec3d(p) + kOrigin);
                         for (int c = 0; c < 3; ++c) {
                             EXPECT_NEAR(mp.Le[c], want[c], tolerance * want.MaxComponent());
                         }
                         ++calls;
                         return true;
                     });
    EXPECT_GT(calls, 50);
}

Rgb Planck(double kelvin) { return BlackbodyRgb(kelvin) * float(BlackbodyLuminance(kelvin) / 683); }

TEST(SceneMedia, BlackbodyEmissionInAbsoluteUnits) {
    const auto density = MakeGrid(
        10, [](int, int, int) { return 1.0f; }, kTilted);
    Medium m = GridMedium(density, Rgb(60.0f), Rgb(0.0f));
    // Its own placement: 3 * 500 K everywhere it is read.
    const Placement hot_at{{100, -49, 20}, Normalize(Vec3d(0, 1, 0)), 0.3, 0.2};
    m.temperature = MakeGrid(
        8, [](int, int, int) { return 3.0f; }, hot_at, 3.0f);
    m.temperature_scale = 500;
    const SceneMedia uniform = OneMedium(m);
    EXPECT_TRUE(uniform.IsEmissive(0));
    const Ray ray = RayBetween(World(*density, {1, 2, 3}), World(*density, {8, 7, 6}));
    ExpectEmission(
        uniform, ray, [](const Vec3d&) { return Planck(1500); }, 1e-5);

    // 2000 K to 5750 K along x, on a lattice 0.7 times the density's (the ray stays inside it),
    // with an emission grid doubling `emission` on top.
    const Placement ramp_at{kTilted.translation, kTilted.axis, kTilted.angle, 0.07};
    const auto temperature = MakeGrid(
        16, [](int x, int, int) { return 2 + 0.25f * float(x); }, ramp_at);
    m.temperature = temperature;
    m.temperature_scale = 1000;
    m.emission = {0.1f, 0.2f, 0.3f};
    m.emission_grid = MakeGrid(
        6, [](int, int, int) { return 2.0f; }, kTilted, 2.0f);
    const SceneMedia ramp = OneMedium(m);
    int hot = 0;
    ExpectEmission(
        ramp, ray,
        [&](const Vec3d& world) {
            const double kelvin =
                1000 * double(temperature->Lookup(temperature->world_to_index.Apply(world)));
            hot += kelvin >= 2000;
            return Rgb(0.2f, 0.4f, 0.6f) + (kelvin > 500 ? Planck(kelvin) : Rgb(0.0f));
        },
        2e-3);
    EXPECT_GT(hot, 50);  // the ray runs through the temperature grid

    // 50 K glows with nothing visible.
    m.emission = Rgb(0.0f);
    m.emission_grid = nullptr;
    m.temperature_scale = 10;
    const SceneMedia cold = OneMedium(m);
    EXPECT_FALSE(cold.IsEmissive(0));
    ExpectEmission(
        cold, ray, [](const Vec3d&) { return Rgb(0.0f); }, 0);
}

}  // namespace
}  // namespace lf
