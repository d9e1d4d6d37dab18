// Progressive photon mapping (lf/kernels/ppm.h) against closed forms: the photon map's queries
// against brute force; the emitted photons' mean power against the lights' analytic power; the
// two furnace spheres (mean radiance 1, no kernel bias on a sphere: the part of a sphere within
// r of a point on it has area pi r^2 exactly); the kernel bias of a caustic under a point light
// shrinking with the radius schedule as predicted; split invariance over passes and tiles.
// Standard errors come from the spread of per-pass image means (photons of a pass are shared
// by its pixels, so pixels are not independent; passes are).
#include "lf/kernels/ppm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/light_emission.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/tile_renderer.h"
#include "test_scenes.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kSigmas = 5;

std::unique_ptr<EmbreeScene> Build(const Scene& scene) {
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    return std::move(*es);
}

using testing::AddQuad;

std::unique_ptr<PpmRenderer> MakePpm(const EmbreeScene& es, const Camera& camera,
                                     const SplatRenderSettings& settings) {
    auto ppm = PpmRenderer::Create(es, camera, settings);
    EXPECT_TRUE(ppm.ok()) << ppm.status();
    return std::move(*ppm);
}

struct PassStatistics {
    double mean[3] = {0, 0, 0};
    double standard_error[3] = {0, 0, 0};
};

// Renders passes [0, passes) of the whole image one by one; the mean over passes of each
// pass's image mean, and its standard error from their spread.
PassStatistics RenderPasses(const PpmRenderer& ppm, const Camera& camera, int passes,
                            RenderStats* stats = nullptr) {
    const PixelRect rect{0, 0, camera.width(), camera.height()};
    std::vector<double> sum(3, 0), sum2(3, 0);
    for (int p = 0; p < passes; ++p) {
        TileSums tile(rect);
        SplatList splats(camera.width(), camera.height());
        ppm.Render({rect, uint64_t(p), uint64_t(p) + 1, uint64_t(p), uint64_t(p) + 1}, tile,
                   splats);
        EXPECT_EQ(splats.MemoryBytes(), 0u);
        if (stats) *stats += tile.stats;
        double m[3] = {0, 0, 0};
        for (const PixelSums& px : tile.pixels) {
            const Rgb v = px.Mean();
            m[0] += v.r;
            m[1] += v.g;
            m[2] += v.b;
        }
        for (int c = 0; c < 3; ++c) {
            m[c] /= double(tile.pixels.size());
            sum[size_t(c)] += m[c];
            sum2[size_t(c)] += m[c] * m[c];
        }
    }
    PassStatistics out;
    for (int c = 0; c < 3; ++c) {
        out.mean[c] = sum[size_t(c)] / passes;
        const double var =
            std::max(0.0, (sum2[size_t(c)] - passes * out.mean[c] * out.mean[c]) / (passes - 1));
        out.standard_error[c] = std::sqrt(var / passes);
    }
    return out;
}

TEST(PhotonMap, QueriesMatchBruteForce) {
    std::vector<Photon> photons;
    uint64_t state = 1;
    auto uniform = [&] { return float(MixBits(++state) >> 40) * 0x1p-24f; };
    for (int i = 0; i < 5000; ++i) {
        // Clustered in a 4 x 4 x 4 box with a few far outliers, ids in power.r.
        const float s = i % 100 == 0 ? 1000.0f : 4.0f;
        photons.push_back({Vec3(s * uniform() - 2, s * uniform() - 2, 4 * uniform() - 2), Vec3(),
                           Rgb(float(i), 1, 0), 1});
    }
    for (float radius : {0.05f, 0.3f, 1.7f}) {
        const PhotonMap map(photons, radius);
        ASSERT_EQ(map.size(), photons.size());
        for (int q = 0; q < 200; ++q) {
            const Vec3 p(5 * uniform() - 2.5f, 5 * uniform() - 2.5f, 5 * uniform() - 2.5f);
            std::vector<int> found, expected;
            map.ForEachWithin(p, [&](const Photon& ph) { found.push_back(int(ph.power.r)); });
            for (const Photon& ph : photons) {
                const Vec3 d = ph.p - p;
                if (Dot(d, d) <= radius * radius) expected.push_back(int(ph.power.r));
            }
            std::sort(found.begin(), found.end());
            ASSERT_EQ(found, expected) << "radius " << radius << " query " << q;
        }
    }
    EXPECT_EQ(PhotonMap({}, 1).size(), 0u);
    int calls = 0;
    PhotonMap({}, 1).ForEachWithin(Vec3(), [&](const Photon&) { ++calls; });
    EXPECT_EQ(calls, 0);
}

// A point light (4 pi I) and a one-sided unit-square emitter (pi Le A): the mean photon power,
// failed samples counting 0, is their sum.
TEST(Ppm, EmittedPhotonPowerSumsToLightPower) {
    Scene scene;
    Material lamp;
    lamp.emission = Rgb(2.0f, 1.0f, 0.5f);
    lamp.reflectance = Rgb(0.0f);
    scene.materials.push_back(lamp);
    AddQuad(scene, 0, {0, 2, 0}, {1, 2, 0}, {1, 2, 1}, {0, 2, 1});
    scene.point_lights.push_back({Vec3d(0, 0, 0), Rgb(1.0f, 2.0f, 3.0f)});
    const auto es = Build(scene);
    const EmissionSampler emission(*es);
    const double expected[3] = {4 * kPi * 1 + kPi * 2, 4 * kPi * 2 + kPi * 1,
                                4 * kPi * 3 + kPi * 0.5};
    constexpr int kPhotons = 200'000;
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int i = 0; i < kPhotons; ++i) {
        Sampler sampler(MixBits(kPhotonSeedSalt), i & 0xffff, i >> 16, 0);
        const std::optional<EmittedPhoton> photon = EmitPhoton(emission, sampler);
        if (!photon) continue;
        const double v[3] = {photon->power.r, photon->power.g, photon->power.b};
        for (int c = 0; c < 3; ++c) {
            sum[c] += v[c];
            sum2[c] += v[c] * v[c];
        }
    }
    for (int c = 0; c < 3; ++c) {
        const double mean = sum[c] / kPhotons;
        const double se = std::sqrt((sum2[c] / kPhotons - mean * mean) / kPhotons);
        EXPECT_NEAR(mean, expected[c], kSigmas * se) << "channel " << c;
    }
}

// A unit sphere of albedo 0.5 seen from inside: L = L_direct / (1 - 0.5) = 1 everywhere, the
// direct part by next-event estimation, the rest by the photons.
Scene FurnaceSphere(float le, bool point_light) {
    Scene scene;
    Material m;
    m.reflectance = Rgb(0.5f);
    m.emission = Rgb(le);
    m.two_sided_emission = le > 0;  // the camera sees the inside, the back face
    scene.materials.push_back(m);
    scene.spheres.push_back({"furnace", 0, Vec3d(), 1});
    if (point_light) scene.point_lights.push_back({Vec3d(), Rgb(float(kPi))});
    scene.camera = testing::SquareCamera({0.1, -0.2, 0.05}, {1, 0.3, 0.7}, {0, 1, 0}, 90, 12);
    return scene;
}

void ExpectFurnaceIsOne(const Scene& scene, SamplerType sampler_type,
                        LightStrategy strategy = LightStrategy::kBvh) {
    const auto es = Build(scene);
    const Camera camera(scene.camera, es->origin());
    SplatRenderSettings settings;
    settings.max_depth = -1;
    settings.photons_per_pass = 20'000;
    settings.initial_radius = 0.15;
    settings.sampler = sampler_type;
    settings.light_strategy = strategy;
    const auto ppm = MakePpm(*es, camera, settings);
    RenderStats stats;
    const PassStatistics s = RenderPasses(*ppm, camera, 16, &stats);
    EXPECT_EQ(stats.invalid_samples, 0u);
    for (int c = 0; c < 3; ++c) {
        std::printf("[furnace] channel %d: %.5f +- %.5f\n", c, s.mean[c], s.standard_error[c]);
        EXPECT_NEAR(s.mean[c], 1.0, kSigmas * s.standard_error[c] + 1e-4) << "channel " << c;
    }
}

TEST(Ppm, PointLightInSphereFurnaceIsOne) {
    ExpectFurnaceIsOne(FurnaceSphere(0, true), SamplerType::kSobol);
    ExpectFurnaceIsOne(FurnaceSphere(0, true), SamplerType::kIndependent);
}

// Under both light strategies: the BVH's sphere-cone sampling from a point on the emitting
// sphere itself once lost light here (0.89 instead of 1).
TEST(Ppm, EmissiveSphereFurnaceIsOne) {
    ExpectFurnaceIsOne(FurnaceSphere(0.5f, false), SamplerType::kSobol, LightStrategy::kPower);
    ExpectFurnaceIsOne(FurnaceSphere(0.5f, false), SamplerType::kSobol, LightStrategy::kBvh);
}

// A caustic with a known kernel bias. A Lambertian floor (rho 0.5) at y = 0, a mirror
// (reflectance 1) at y = 2, a point light of intensity 1 at y = 1: at max_depth 2 the floor's
// radiance is rho / pi (E_direct + E_mirror), E_mirror from the light's image at height
// h = 3, which only the photons carry: E_mirror(x) = h / (h^2 + x^2)^(3/2). A pass's density
// estimate at x = 0 is the mean of E_mirror over the disk of radius r_p,
// 2 h / r^2 (1 / h - 1 / sqrt(h^2 + r^2)), below the peak 1 / h^2 by about 3 r^2 / (4 h^4) x
// the peak: the kernel bias. The image's expectation after N passes is the mean of the
// passes' disk means, and its error against the exact peak falls as r_N^2 does.
TEST(Ppm, CausticBiasShrinksWithPassesAsPredicted) {
    Scene scene;
    Material floor;
    floor.reflectance = Rgb(0.5f);
    scene.materials.push_back(floor);
    Material mirror;
    mirror.type = Material::Type::kMirror;
    mirror.reflectance = Rgb(1.0f);
    scene.materials.push_back(mirror);
    const double s = 20;
    AddQuad(scene, 0, {-s, 0, -s}, {-s, 0, s}, {s, 0, s}, {s, 0, -s});  // normal +y
    AddQuad(scene, 1, {-s, 2, -s}, {s, 2, -s}, {s, 2, s}, {-s, 2, s});  // normal -y
    scene.point_lights.push_back({Vec3d(0, 1, 0), Rgb(1.0f)});
    // A narrow view of the floor under the light: |x|, |z| <= 1.5 tan(1 deg) = 0.026.
    scene.camera = testing::SquareCamera({0, 1.5, 0}, {0, 0, 0}, {0, 0, 1}, 2, 8);
    const auto es = Build(scene);
    const Camera camera(scene.camera, es->origin());
    SplatRenderSettings settings;
    settings.max_depth = 2;
    settings.photons_per_pass = 50'000;
    settings.initial_radius = 1.5;
    settings.sampler = SamplerType::kIndependent;
    const auto ppm = MakePpm(*es, camera, settings);

    const double h = 3, rho_over_pi = 0.5 / kPi;
    // Direct light averaged over the image's footprint (a fine grid).
    const double a = 1.5 * std::tan(kPi / 180);
    double direct = 0;
    constexpr int kGrid = 64;
    for (int j = 0; j < kGrid; ++j) {
        for (int i = 0; i < kGrid; ++i) {
            const double x = a * (2 * (i + 0.5) / kGrid - 1), z = a * (2 * (j + 0.5) / kGrid - 1);
            direct += std::pow(1 + x * x + z * z, -1.5) / (kGrid * kGrid);
        }
    }
    const double exact = rho_over_pi * (direct + 1 / (h * h));
    double previous_error = 1e30;
    for (int passes : {4, 16, 64}) {
        double disk_mean = 0;
        for (int p = 0; p < passes; ++p) {
            const double r2 = 1.5 * 1.5 * PpmRadiusRatioSquared(settings.alpha, uint64_t(p));
            disk_mean += 2 * h / r2 * (1 / h - 1 / std::sqrt(h * h + r2)) / passes;
        }
        const double expected = rho_over_pi * (direct + disk_mean);
        const PassStatistics stats = RenderPasses(*ppm, camera, passes);
        const double error = exact - stats.mean[0];
        std::printf("[caustic] %2d passes: %.6f +- %.6f, predicted %.6f, exact %.6f\n", passes,
                    stats.mean[0], stats.standard_error[0], expected, exact);
        // The footprint's spread of E_mirror (x^2 / h^2 < 1e-4) is far below the tolerance.
        EXPECT_NEAR(stats.mean[0], expected, kSigmas * stats.standard_error[0] + 1e-4 * exact)
            << passes << " passes";
        EXPECT_GT(error, 0) << passes << " passes: the kernel underestimates a peak";
        EXPECT_LT(error, previous_error) << passes << " passes";
        previous_error = error;
    }
}

// The same bits whether a tile's passes run in one work item or several, and whether the
// image is one tile or several.
TEST(Ppm, SplitsOverPassesAndTilesGiveTheSameBits) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene->camera.width = scene->camera.height = 12;
    const auto es = Build(*scene);
    const Camera camera(scene->camera, es->origin());
    SplatRenderSettings settings;
    settings.photons_per_pass = 3000;
    settings.max_depth = -1;
    const auto ppm = MakePpm(*es, camera, settings);
    EXPECT_GT(ppm->initial_radius(), 0);
    SplatList splats(12, 12);
    const PixelRect all{0, 0, 12, 12};
    TileSums whole(all);
    ppm->Render({all, 0, 4, 0, 4}, whole, splats);
    TileSums split(all);
    ppm->Render({all, 0, 1, 0, 1}, split, splats);
    TileSums rest(all);
    ppm->Render({all, 1, 4, 1, 4}, rest, splats);
    split += rest;
    EXPECT_EQ(whole.stats.samples, 12u * 12u * 4u);
    for (int y = 0; y < 12; ++y) {
        for (int x = 0; x < 12; ++x) {
            for (int h = 0; h < 2; ++h) {
                ASSERT_EQ(whole.at(x, y).count[h], split.at(x, y).count[h]);
                for (int c = 0; c < 3; ++c) {
                    ASSERT_EQ(whole.at(x, y).sum[h][c], split.at(x, y).sum[h][c]) << x << ", " << y;
                }
            }
        }
    }
    for (const PixelRect& r :
         {PixelRect{0, 0, 12, 5}, PixelRect{0, 5, 7, 7}, PixelRect{7, 5, 5, 7}}) {
        TileSums tile(r);
        ppm->Render({r, 0, 4, 0, 4}, tile, splats);
        for (int y = r.y0; y < r.y0 + r.height; ++y) {
            for (int x = r.x0; x < r.x0 + r.width; ++x) {
                for (int h = 0; h < 2; ++h) {
                    for (int c = 0; c < 3; ++c) {
                        ASSERT_EQ(whole.at(x, y).sum[h][c], tile.at(x, y).sum[h][c])
                            << x << ", " << y;
                    }
                }
            }
        }
    }
    EXPECT_GT(whole.at(6, 6).Mean().Average(), 0);
}

TEST(Ppm, RejectsAlphaOutsideTheUnitInterval) {
    Scene scene = FurnaceSphere(0, true);
    const auto es = Build(scene);
    const Camera camera(scene.camera, es->origin());
    SplatRenderSettings settings;
    settings.alpha = 1;
    const auto ppm = PpmRenderer::Create(*es, camera, settings);
    ASSERT_FALSE(ppm.ok());
    EXPECT_EQ(ppm.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(ppm.status().message().find("ppm"), std::string::npos);
}

}  // namespace
}  // namespace lf

namespace lf {
namespace {

// Block means (4 x 4 blocks) of G over the passes [0, passes) of a ppm image.
std::vector<double> PpmBlockMeans(const PpmRenderer& ppm, const Camera& camera, int passes) {
    const PixelRect rect{0, 0, camera.width(), camera.height()};
    TileSums tile(rect);
    SplatList splats(camera.width(), camera.height());
    ppm.Render({rect, 0, uint64_t(passes), 0, uint64_t(passes)}, tile, splats);
    std::vector<double> blocks(size_t(camera.width() / 4 * (camera.height() / 4)), 0);
    for (int y = 0; y < camera.height(); ++y) {
        for (int x = 0; x < camera.width(); ++x) {
            blocks[size_t(y / 4 * (camera.width() / 4) + x / 4)] += tile.at(x, y).Mean().g / 16;
        }
    }
    return blocks;
}

// ppm approaches the path tracer as passes grow (the "show the bias shrinking"): on the
// Cornell box at 16 x 16, block by block against a path-traced image of 4096 spp, the RMS
// difference of the block means falls from 4 to 16 to 256 passes. Both the kernel bias (r_N^2
// ~ N^(alpha - 1)) and the noise (N^-alpha) fall; 4 -> 256 passes is 64^(1/3) = 4x for both at
// alpha 2/3, so the last is asked to be below half the first.
TEST(Ppm, ApproachesThePathTracerOnTheCornellBoxAsPassesGrow) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene->camera.width = scene->camera.height = 16;
    const auto es = Build(*scene);
    const Camera camera(scene->camera, es->origin());
    const PathTracer path(*es, -1);
    const TileSums reference =
        RenderTile(camera, path, PixelRect{0, 0, 16, 16}, 9, 0, 4096, {0, 0, SamplerType::kSobol});
    std::vector<double> expected(16, 0);
    for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 16; ++x)
            expected[size_t(y / 4 * 4 + x / 4)] += reference.at(x, y).Mean().g / 16;
    }
    SplatRenderSettings settings;
    settings.max_depth = -1;
    settings.photons_per_pass = 16'384;
    const auto ppm = MakePpm(*es, camera, settings);
    std::vector<double> rms;
    for (const int passes : {4, 16, 256}) {
        const std::vector<double> blocks = PpmBlockMeans(*ppm, camera, passes);
        double sum = 0;
        for (size_t b = 0; b < blocks.size(); ++b) sum += std::pow(blocks[b] - expected[b], 2);
        rms.push_back(std::sqrt(sum / double(blocks.size())));
        std::printf("[cornell] %d passes: block RMS difference %.5f\n", passes, rms.back());
    }
    EXPECT_LT(rms[1], rms[0]);
    EXPECT_LT(rms[2], 0.5 * rms[0]);
}

// A smooth principled sphere over a black diffuse base (IOR 2.5, F0 = 0.18) above a lit floor,
// the camera seeing only the sphere: every pixel's radiance is the sphere's delta reflection
// of the floor, the quad light and the black sky, which photon mapping used to drop (it
// gathered at the sphere's base, which reflects nothing, and stopped). The path tracer at
// 4096 spp, in 16 independent batches, is the reference; both estimate the same image up to
// the photon kernel's bias on the floor's caustic (the sphere's reflection of the light),
// a fraction of a percent of the mean here: the tolerance is 5 combined standard errors plus
// 1% of the mean for it.
TEST(Ppm, FollowsTheDeltaLobeOfASmoothSurfaceOverADiffuseBase) {
    Scene scene;
    Material floor;
    floor.type = Material::Type::kLambert;
    floor.reflectance = Rgb(0.7f, 0.6f, 0.3f);
    Material plastic;
    plastic.type = Material::Type::kPrincipled;
    plastic.reflectance = Rgb(0.0f);
    plastic.roughness = 0;
    plastic.ior = 2.5f;
    Material lamp;
    lamp.type = Material::Type::kLambert;
    lamp.reflectance = Rgb(0.0f);
    lamp.emission = Rgb(30.0f);
    scene.materials = {floor, plastic, lamp};
    AddQuad(scene, 0, {-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20});  // normal +y
    AddQuad(scene, 2, {-0.5, 4, 1}, {0.5, 4, 1}, {0.5, 4, 2}, {-0.5, 4, 2});    // normal -y
    scene.spheres.push_back({"plastic", 1, Vec3d(0, 1, 0), 1});
    scene.camera = testing::SquareCamera({0, 1.5, 5}, {0, 1, 0}, {0, 1, 0}, 12, 8);
    const auto es = Build(scene);
    const Camera camera(scene.camera, es->origin());
    const PixelRect rect{0, 0, 8, 8};

    const PathTracer path(*es, -1);
    constexpr int kBatches = 16;
    double path_sum[3] = {0, 0, 0}, path_sum2[3] = {0, 0, 0};
    for (int b = 0; b < kBatches; ++b) {
        const TileSums tile = RenderTile(camera, path, rect, 5, uint64_t(b) * 256,
                                         uint64_t(b + 1) * 256, {0, 0, SamplerType::kSobol});
        double m[3] = {0, 0, 0};
        for (const PixelSums& px : tile.pixels) {
            const Rgb v = px.Mean();
            m[0] += v.r / 64;
            m[1] += v.g / 64;
            m[2] += v.b / 64;
        }
        for (int c = 0; c < 3; ++c) {
            path_sum[c] += m[c];
            path_sum2[c] += m[c] * m[c];
        }
    }
    SplatRenderSettings settings;
    settings.max_depth = -1;
    settings.photons_per_pass = 16'384;
    const auto ppm = MakePpm(*es, camera, settings);
    const PassStatistics photons = RenderPasses(*ppm, camera, 64);
    for (int c = 0; c < 3; ++c) {
        const double mean = path_sum[c] / kBatches;
        const double path_se =
            std::sqrt(std::max(0.0, path_sum2[c] / kBatches - mean * mean) / (kBatches - 1));
        const double se = std::hypot(path_se, photons.standard_error[c]);
        std::printf("[smooth base] channel %d: path %.5f +- %.5f, ppm %.5f +- %.5f\n", c, mean,
                    path_se, photons.mean[c], photons.standard_error[c]);
        EXPECT_GT(mean, 0.005) << "the sphere must show a lit reflection";
        EXPECT_NEAR(photons.mean[c], mean, kSigmas * se + 0.01 * mean) << "channel " << c;
    }
}

}  // namespace
}  // namespace lf
