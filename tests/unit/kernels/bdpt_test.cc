// Bidirectional path tracing (lf/kernels/bdpt.h) against analytic answers and the path tracer:
// two furnace spheres whose mean radiance is 1 (a point light of intensity pi at the centre of
// an albedo-0.5 unit sphere; an emissive interior of 0.5), region-by-region agreement with the
// path tracer on the Cornell box, the materials scene (mirror, glass, glossy spheres) and scenes
// lit by a point and a directional light, and bit-identical sums for any split of the work.
// Tolerances come from the estimators' own variance: the A/B half estimates of every pixel.
#include "lf/kernels/bdpt.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "bdpt_render.h"
#include "bonferroni.h"
#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/local/method_factory.h"
#include "render_path.h"
#include "test_scenes.h"

namespace lf {
namespace {

using testing::BdptFrame;
using testing::CompareWithPathTracer;
using testing::LoadSmall;
using testing::Mean;
using testing::RenderBdpt;
using testing::SplatMean;

// A unit sphere about the origin, albedo 0.5 on both faces, seen from inside.
Scene FurnaceSphere(float le) {
    Scene scene;
    Material m;
    m.name = "furnace";
    m.reflectance = Rgb(0.5f);
    m.double_sided = true;
    m.emission = Rgb(le);
    m.two_sided_emission = le > 0;
    scene.materials.push_back(m);
    scene.spheres.push_back({"shell", 0, Vec3d(0, 0, 0), 1});
    scene.camera = testing::SquareCamera({0.1, -0.2, 0.05}, {1, 0.3, 0.7}, {0, 1, 0}, 90, 24);
    return scene;
}

TEST(Bdpt, FurnaceSphereWithAPointLightHasMeanRadianceOne) {
    Scene scene = FurnaceSphere(0);
    // Irradiance pi / 1^2 straight from the light, so radiance 0.5 once reflected and
    // 0.5 / (1 - 0.5) = 1 over all bounces.
    scene.point_lights.push_back({{0, 0, 0}, Rgb(std::numbers::pi_v<float>)});
    const BdptFrame f = RenderBdpt(scene, 64, -1);
    const Mean m = SplatMean(f);
    std::printf("[bdpt] point-lit furnace: %.5f +- %.5f\n", m.value, m.error);
    EXPECT_NEAR(m.value, 1.0, 5 * m.error);
    EXPECT_LT(m.error, 0.01);
    EXPECT_EQ(f.stats.samples, uint64_t(24 * 24 * 64));
    EXPECT_EQ(f.stats.invalid_samples, 0u);
}

TEST(Bdpt, FurnaceSphereWithAnEmissiveInteriorHasMeanRadianceOne) {
    const Scene scene = FurnaceSphere(0.5f);
    const BdptFrame f = RenderBdpt(scene, 64, -1);
    const Mean m = SplatMean(f);
    std::printf("[bdpt] emissive furnace: %.5f +- %.5f\n", m.value, m.error);
    EXPECT_NEAR(m.value, 1.0, 5 * m.error);
    EXPECT_LT(m.error, 0.01);
}

TEST(Bdpt, FurnaceWithAMaxDepthSumsItsBounces) {
    // max_depth 2: emission plus two bounces, 0.5 (1 + 0.5 + 0.25).
    const Scene scene = FurnaceSphere(0.5f);
    const Mean m = SplatMean(RenderBdpt(scene, 64, 2));
    std::printf("[bdpt] emissive furnace, max depth 2: %.5f +- %.5f\n", m.value, m.error);
    EXPECT_NEAR(m.value, 0.875, 5 * m.error);
}

// A furnace of reflectance 1 (roulette never ends a path) with unlimited depth: every subpath
// runs to the cap, kBdptUnlimitedDepth bounces, and is counted as cut; the render ends (with
// 65536 vertices a subpath one sample took minutes) and is finite: the emission summed over at
// most the bounces two capped subpaths join, 0.5 (1 + 2 x 128). A hang here is the failure.
TEST(Bdpt, WhiteFurnaceWithUnlimitedDepthStopsAtTheCap) {
    Scene scene = FurnaceSphere(0.5f);
    scene.materials[0].reflectance = Rgb(1.0f);
    scene.camera.width = scene.camera.height = 2;
    const BdptFrame f = RenderBdpt(scene, 2, -1);  // one sample in each half
    EXPECT_GT(f.stats.truncated_paths, 0u);
    EXPECT_EQ(f.stats.invalid_samples, 0u);
    const Mean m = SplatMean(f);
    EXPECT_GT(m.value, 0.5);
    EXPECT_LE(m.value, 0.5 * (1 + 2 * kBdptUnlimitedDepth));
}

TEST(Bdpt, MatchesThePathTracerOnTheCornellBox) {
    CompareWithPathTracer("cornell_box", LoadSmall("cornell_box.json", 32), 256, 256, 5);
}

// The materials scene lit by its lamp alone: its point light shines through the glass and off
// the mirror onto the floor, caustics the path tracer cannot render (see below).
Scene MaterialsUnderTheLamp(int size) {
    Scene scene = LoadSmall("materials.json", size);
    scene.point_lights.clear();
    return scene;
}

TEST(Bdpt, MatchesThePathTracerOnMirrorGlassAndGlossySpheres) {
    CompareWithPathTracer("materials", MaterialsUnderTheLamp(32), 256, 512, 8);
}

TEST(Bdpt, RendersThePointLightCausticThePathTracerMisses) {
    // The point light of materials.json alone: light focused by the glass sphere onto the
    // floor reaches the camera only along light -> glass -> glass -> floor -> camera, which the
    // path tracer cannot sample (it would have to hit the point by BSDF sampling) and light
    // tracing (t = 1) does. Elsewhere the two agree; in the 8 x 8 block of the caustic's
    // centre BDPT is brighter by many standard errors.
    Scene scene = LoadSmall("materials.json", 32);
    for (Material& m : scene.materials) m.emission = Rgb(0);
    const BdptFrame bd = RenderBdpt(scene, 256, 8);
    const RenderOutput pt = testing::RenderPath(scene, 512, 8, 3).out;
    // Block (2, 3) of the 32 x 32 frame: x 16..23, y 24..31, the floor around the point
    // where the light's caustic lands, in front of the sphere.
    const testing::BlockMeans block = testing::CompareBlock(bd, pt.image, 16, 24, 8);
    const double m1 = block.bdpt, m2 = block.path, se = block.se;
    std::printf("[bdpt] point-light caustic block: bdpt %.5f, path %.5f +- %.5f\n", m1, m2, se);
    EXPECT_GT(m1 - m2, 5 * se);
}

// The caustic of a small area lamp through a glass ball (tests/scenes/caustic.json at 32 x 32:
// the Cornell box, a 4 cm lamp, the glass ball standing on the floor). Its floor pixels are lit
// along E D S S L; the path tracer samples that only by hitting the lamp through the ball (rare,
// each hit worth ~70), light tracing (t = 1) always (each splat ~0.07). With the right MIS
// weights light tracing carries the caustic and BDPT's per-sample variance there is hundreds of
// times below the path tracer's (728x here; 1406x with 16x the samples, where the means are
// 0.1454 +- 0.0005 and 0.1436 +- 0.0064). pbrt's remap of delta densities gave the camera paths
// weights near 1 next to the ball's foot, and BDPT was noisier than the path tracer (3.3 against
// 1.7). The mean must still agree with the path tracer's. Variances from independent seeds:
// the region mean of each frame, its spread over the seeds.
TEST(Bdpt, LightTracingCarriesTheCausticOfASmallLampThroughGlass) {
    const Scene scene = LoadSmall("caustic.json", 32);
    // The caustic's floor pixels in front of the ball's foot (tools/method_bench.sh's region
    // at this size). Not row 28: its pixels hold the ball's bottom, through which the camera
    // sees the floor (E S S D S S L), a path only s = 0 can make, for BDPT as for the path
    // tracer.
    const int x0 = 19, x1 = 23, y0 = 29, y1 = 29;
    const auto region_mean = [&](const auto& pixel) {
        double sum = 0;
        for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) sum += pixel(x, y);
        }
        return sum / ((x1 - x0 + 1) * (y1 - y0 + 1));
    };
    struct Stats {
        double mean = 0, per_sample_var = 0, se = 0;
    };
    // Mean over the seeds' region means, the variance of one camera sample's contribution to
    // the region mean (the seeds' variance times spp) and the standard error of the mean.
    const auto stats = [](const std::vector<double>& means, uint64_t spp) {
        Stats s;
        const double k = double(means.size());
        for (double m : means) s.mean += m / k;
        double var = 0;
        for (double m : means) var += (m - s.mean) * (m - s.mean) / (k - 1);
        s.per_sample_var = var * double(spp);
        s.se = std::sqrt(var / k);
        return s;
    };
    constexpr int kSeeds = 8;
    constexpr uint64_t kSpp = 64, kPathSpp = 256;
    std::vector<double> bdpt_means, path_means;
    for (int seed = 0; seed < kSeeds; ++seed) {
        const BdptFrame bd = RenderBdpt(scene, kSpp, 5, 100 + uint64_t(seed));
        bdpt_means.push_back(region_mean([&](int x, int y) { return bd.Mean(x, y).Average(); }));
        const RenderOutput pt = testing::RenderPath(scene, kPathSpp, 5, 200 + uint64_t(seed)).out;
        path_means.push_back(region_mean([&](int x, int y) {
            return (pt.image.Pixel(x, y, "A.").Average() + pt.image.Pixel(x, y, "B.").Average()) /
                   2;
        }));
    }
    const Stats bdpt = stats(bdpt_means, kSpp), path = stats(path_means, kPathSpp);
    std::printf(
        "[bdpt] lamp caustic: bdpt %.4f +- %.4f (per-sample variance %.4g), path %.4f +- "
        "%.4f (%.4g): %.0fx lower\n",
        bdpt.mean, bdpt.se, bdpt.per_sample_var, path.mean, path.se, path.per_sample_var,
        path.per_sample_var / bdpt.per_sample_var);
    EXPECT_LT(5 * bdpt.per_sample_var, path.per_sample_var);
    EXPECT_NEAR(bdpt.mean, path.mean, 4 * std::sqrt(bdpt.se * bdpt.se + path.se * path.se));
}

TEST(Bdpt, MatchesThePathTracerUnderAPointLight) {
    // The Cornell box lit by a point light under its ceiling instead of its lamp (delta
    // position: no s = 0, light paths start at the point). Diffuse only: the path tracer cannot
    // see a delta light through a mirror or glass (a caustic BDPT renders), so the materials
    // scene would not compare.
    Scene scene = LoadSmall("cornell_box.json", 32);
    for (Material& m : scene.materials) m.emission = Rgb(0);
    scene.point_lights.push_back({{0.278, 0.45, 0.28}, Rgb(0.4f, 0.3f, 0.2f)});
    CompareWithPathTracer("point light", scene, 256, 512, 6);
}

TEST(Bdpt, MatchesThePathTracerUnderADirectionalLight) {
    // An open scene (floor, back wall, spheres) under a delta directional light: light paths
    // start on the disk outside the scene; no strategy can hit the light.
    Scene scene;
    Material white;
    white.reflectance = Rgb(0.7f);
    scene.materials.push_back(white);
    Material glossy;
    glossy.type = Material::Type::kGlossy;
    glossy.roughness = 0.3f;
    glossy.reflectance = Rgb(0.5f);
    scene.materials.push_back(glossy);
    Material red;  // not glass: the path tracer misses the caustics of a delta light
    red.reflectance = Rgb(0.6f, 0.1f, 0.1f);
    scene.materials.push_back(red);
    TriangleMesh floor;
    floor.material = 0;
    floor.positions = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    floor.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(floor);
    TriangleMesh wall;
    wall.material = 0;
    wall.positions = {{-2, 0, 1}, {2, 0, 1}, {2, 2, 1}, {-2, 2, 1}};
    wall.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(wall);
    scene.spheres.push_back({"glossy", 1, {-0.5, 0.4, 0}, 0.4});
    scene.spheres.push_back({"red", 2, {0.5, 0.4, -0.2}, 0.4});
    scene.directional_lights.push_back({Normalize(Vec3d(0.3, -1, 0.4)), Rgb(2, 1.8f, 1.5f), 0});
    scene.camera = testing::SquareCamera({0, 1.2, -3}, {0, 0.4, 0}, {0, 1, 0}, 45, 32);
    CompareWithPathTracer("directional light", scene, 256, 512, 6);
}

// An open scene: a floor, a back wall, a glossy and a diffuse sphere, lit by whatever the
// caller adds.
Scene OpenScene() {
    Scene scene;
    Material white;
    white.reflectance = Rgb(0.7f);
    scene.materials.push_back(white);
    Material glossy;
    glossy.type = Material::Type::kGlossy;
    glossy.roughness = 0.3f;
    glossy.reflectance = Rgb(0.5f);
    scene.materials.push_back(glossy);
    Material red;
    red.reflectance = Rgb(0.6f, 0.1f, 0.1f);
    scene.materials.push_back(red);
    TriangleMesh floor;
    floor.material = 0;
    floor.positions = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    floor.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(floor);
    TriangleMesh wall;
    wall.material = 0;
    wall.positions = {{-2, 0, 1}, {2, 0, 1}, {2, 2, 1}, {-2, 2, 1}};
    wall.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(wall);
    scene.spheres.push_back({"glossy", 1, {-0.5, 0.4, 0}, 0.4});
    scene.spheres.push_back({"red", 2, {0.5, 0.4, -0.2}, 0.4});
    scene.camera = testing::SquareCamera({0, 1.2, -3}, {0, 0.4, 0}, {0, 1, 0}, 45, 32);
    return scene;
}

TEST(Bdpt, MatchesThePathTracerUnderASkyAndASunDisk) {
    // Lights at infinity: camera paths that escape see them (s = 0), light paths start on the
    // disk outside the scene, weighed as one light as the LightSampler does.
    Scene scene = OpenScene();
    scene.environment = EnvironmentLight{};
    scene.environment->radiance = Rgb(0.3f, 0.4f, 0.6f);
    scene.directional_lights.push_back(
        {Normalize(Vec3d(-0.4, -1, 0.3)), Rgb(2, 1.8f, 1.5f), 5 * std::numbers::pi / 180});
    CompareWithPathTracer("sky and sun", scene, 256, 512, 6);
}

TEST(Bdpt, MatchesThePathTracerUnderASpotLight) {
    Scene scene = OpenScene();
    SpotLight spot;
    spot.position = {0.3, 1.8, -0.8};
    spot.direction = Normalize(Vec3d(-0.3, -1, 0.5));
    spot.intensity = Rgb(3, 2.5f, 2);
    spot.inner_cone = 0.3;
    spot.outer_cone = 0.5;
    scene.spot_lights.push_back(spot);
    CompareWithPathTracer("spot light", scene, 256, 512, 6);
}

TEST(Bdpt, MatchesThePathTracerThroughAThinLensAndAbsorbingGlass) {
    // The camera's lens (t = 1 connections sample a lens point) and Beer's law in the glass
    // sphere, on both subpaths and on connections through it.
    Scene scene = MaterialsUnderTheLamp(32);
    scene.camera.aperture_radius = 0.01;
    scene.camera.focus_distance = 1.0;
    for (Material& m : scene.materials) {
        if (m.type == Material::Type::kDielectric) {
            m.attenuation_color = Rgb(0.3f, 0.6f, 0.9f);
            m.attenuation_distance = 0.1f;
        }
    }
    AddAttenuationMedia(scene);
    CompareWithPathTracer("thin lens, absorbing glass", scene, 256, 512, 8);
}

TEST(Bdpt, MatchesThePathTracerThroughTintedPrincipledGlass) {
    // The principled BTDF's base colour tint (per crossing) and Beer's law in a solid sphere, a
    // thin-walled one beside it; both subpaths and the connections cross them.
    Scene scene = OpenScene();
    scene.environment = EnvironmentLight{};
    scene.environment->radiance = Rgb(0.3f, 0.4f, 0.6f);
    scene.directional_lights.push_back({Normalize(Vec3d(0.3, -1, 0.4)), Rgb(2, 1.8f, 1.5f), 0});
    for (int i : {1, 2}) {
        Material& m = scene.materials[size_t(i)];
        m.type = Material::Type::kPrincipled;
        m.reflectance = i == 1 ? Rgb(0.9f, 0.4f, 0.2f) : Rgb(0.3f, 0.8f, 0.5f);
        m.roughness = 0.3f;
        m.transmission = 1;
        m.thickness = i == 1 ? 0.5f : 0;
        m.attenuation_color = Rgb(0.9f, 0.7f, 0.5f);
        m.attenuation_distance = 0.5f;
    }
    AddAttenuationMedia(scene);
    CompareWithPathTracer("tinted principled glass", scene, 256, 512, 8);
}

// Also through media, whose delta and ratio tracking draw from each sample's own stream.
TEST(Bdpt, AnySplitOfTheWorkGivesTheSameBits) {
    for (const char* file : {"materials.json", "media/cornell_fog.json"}) {
        SCOPED_TRACE(file);
        const Scene scene = LoadSmall(file, 16);
        auto es = EmbreeScene::Build(scene);
        ASSERT_TRUE(es.ok());
        const Camera camera(scene.camera, (*es)->origin());
        SplatRenderSettings settings;
        settings.max_depth = 6;
        settings.seed = 11;
        const BdptRenderer renderer(**es, camera, settings);
        const PixelRect rect{0, 0, 16, 16};
        TileSums whole(rect);
        SplatList whole_splats(16, 16);
        renderer.Render(SplatWork{rect, 0, 6, 0, 0}, whole, whole_splats);

        // The same samples as two sample ranges over two halves of the rect, merged.
        TileSums merged(rect);
        SplatList merged_splats(16, 16);
        for (const PixelRect part : {PixelRect{0, 0, 16, 7}, PixelRect{0, 7, 16, 9}}) {
            for (const auto& [begin, end] : {std::pair<uint64_t, uint64_t>{0, 4}, {4, 6}}) {
                TileSums sums(part);
                SplatList splats(16, 16);
                renderer.Render(SplatWork{part, begin, end, 0, 0}, sums, splats);
                for (int y = part.y0; y < part.y0 + part.height; ++y) {
                    for (int x = 0; x < 16; ++x) merged.at(x, y) += sums.at(x, y);
                }
                merged.stats += sums.stats;
                merged_splats += splats;
            }
        }
        for (int y = 0; y < 16; ++y) {
            for (int x = 0; x < 16; ++x) {
                const PixelSums& a = whole.at(x, y);
                const PixelSums& b = merged.at(x, y);
                for (int h = 0; h < 2; ++h) {
                    EXPECT_EQ(a.count[h], b.count[h]);
                    for (int c = 0; c < 3; ++c)
                        EXPECT_EQ(a.sum[h][c], b.sum[h][c]) << x << ", " << y;
                }
            }
        }
        EXPECT_EQ(whole.stats.rays, merged.stats.rays);
        EXPECT_EQ(whole.stats.samples, merged.stats.samples);
        EXPECT_FALSE(whole_splats.entries().empty());
        EXPECT_EQ(whole_splats.entries(), merged_splats.entries());
    }
}

TEST(Bdpt, RefusesPixelFiltersOtherThanTheBox) {
    Scene scene = FurnaceSphere(0.5f);
    scene.camera.filter.type = PixelFilter::Type::kGaussian;
    scene.camera.filter.width = 2;
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const Camera camera(scene.camera, (*es)->origin());
    auto renderer = MakeSplatRenderer(Method::kBdpt, **es, camera, SplatRenderSettings{});
    ASSERT_FALSE(renderer.ok());
    EXPECT_EQ(renderer.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(renderer.status().message().find("bdpt"), std::string::npos);
    EXPECT_NE(renderer.status().message().find("gaussian"), std::string::npos);
}

}  // namespace
}  // namespace lf
