// Light tracing (lf/kernels/light_tracer.h): pbrt-v4's furnace spheres, agreement with the path
// tracer region by region, split invariance, and the splatting-method factory.
#include "lf/kernels/light_tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "bonferroni.h"
#include "lf/core/scene_loader.h"
#include "lf/local/method_factory.h"
#include "render_path.h"
#include "splat_render.h"
#include "splat_scenes.h"

namespace lf {
namespace {

using testing::BonferroniZ;

// The image mean of R, G, B averaged, over K independent batches of light paths, with its
// standard error from the spread of the batch means.
testing::MeanAndError BatchedSplatMean(const Scene& scene, const SplatRenderSettings& settings,
                                       int batches, uint64_t paths_per_batch) {
    const testing::SplatSetup s = testing::MakeSplatSetup(scene, "light", settings);
    std::vector<double> means;
    for (int b = 0; b < batches; ++b) {
        const uint64_t begin = uint64_t(b) * paths_per_batch;
        const Image image =
            testing::RenderSplatPaths(*s.renderer, *s.camera, begin, begin + paths_per_batch).image;
        double sum = 0;
        for (const char* c : {"R", "G", "B"}) {
            for (float v : *image.FindChannel(c)) sum += v;
        }
        means.push_back(sum / (3.0 * image.width() * image.height()));
    }
    double mean = 0, var = 0;
    for (double m : means) mean += m / batches;
    for (double m : means) var += (m - mean) * (m - mean) / (batches - 1);
    return {mean, std::sqrt(var / batches)};
}

SplatRenderSettings Unlimited() {
    SplatRenderSettings settings;
    settings.max_depth = -1;
    settings.seed = 7;
    return settings;
}

// The furnace sphere's image mean is 1 within 4.5 standard errors, which are small enough for
// that to mean something.
void ExpectFurnaceIsOne(const Scene& scene, const char* what) {
    const testing::MeanAndError m = BatchedSplatMean(scene, Unlimited(), 32, 1 << 15);
    std::printf("[light] %s: %.5f +- %.5f (expected 1)\n", what, m.mean, m.standard_error);
    EXPECT_NEAR(m.mean, testing::kFurnaceSphereRadiance, 4.5 * m.standard_error) << what;
    EXPECT_LT(m.standard_error, 0.01) << what << ": too few paths for the test to mean anything";
}

// pbrt-v4's test: inside a sphere of albedo 0.5 lit by a point light of intensity pi at its
// centre the radiance is 1 everywhere.
TEST(LightTracer, PointLitFurnaceSphereIsOne) {
    ExpectFurnaceIsOne(testing::PointLitFurnaceSphere(16), "point-lit furnace sphere");
}

// The same sphere emitting Le = 0.5 instead: L = 1, the emitter seen directly (the light
// vertex connected to the camera) plus every bounce.
TEST(LightTracer, EmissiveFurnaceSphereIsOne) {
    ExpectFurnaceIsOne(testing::EmissiveFurnaceSphere(16), "emissive furnace sphere");
}

// max_depth 0 leaves the emitter seen directly: Le = 0.5, with no noise at all but the
// estimator's (each pixel's value is Le for a box filter, up to the splat count).
TEST(LightTracer, DepthZeroIsTheEmitterSeenDirectly) {
    const Scene scene = testing::EmissiveFurnaceSphere(16);
    SplatRenderSettings settings = Unlimited();
    settings.max_depth = 0;
    const testing::MeanAndError m = BatchedSplatMean(scene, settings, 16, 1 << 14);
    EXPECT_NEAR(m.mean, 0.5, 4.5 * m.standard_error + 1e-6);
}

// --clamp bounds each splat as the path tracer bounds a camera sample: a splat's share of its
// pixel is splat x W H / N, the same as a camera sample's radiance / spp when N = W H spp light
// paths, so the limit is the clamp itself. A clamp far above the furnace's splats (a few units)
// leaves the mean at 1; dividing the limit by W H (as the tracer once did) darkened it tenfold.
TEST(LightTracer, ClampFarAboveTheSplatsLeavesTheFurnaceAtOne) {
    SplatRenderSettings settings = Unlimited();
    settings.clamp = 100;
    const testing::MeanAndError m =
        BatchedSplatMean(testing::PointLitFurnaceSphere(16), settings, 32, 1 << 15);
    std::printf("[light] clamp 100: %.5f +- %.5f (expected 1)\n", m.mean, m.standard_error);
    EXPECT_NEAR(m.mean, testing::kFurnaceSphereRadiance, 4.5 * m.standard_error);
}

Scene LoadTestScene(const char* name, int size) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/" + name);
    EXPECT_TRUE(scene.ok()) << scene.status();
    scene->camera.width = scene->camera.height = size;
    return *std::move(scene);
}

// One work item and the same paths in sub-ranges (odd sizes, across chunk boundaries) give the
// same splat list, entry for entry, and the same counts.
TEST(LightTracer, AnySplitGivesTheSameSplats) {
    const Scene scene = LoadTestScene("materials.json", 24);
    const testing::SplatSetup s = testing::MakeSplatSetup(scene, "light", Unlimited());
    const int w = s.camera->width(), h = s.camera->height();
    constexpr uint64_t kPaths = 20000;
    SplatList whole(w, h);
    TileSums whole_sums(PixelRect{});
    s.renderer->Render({PixelRect{}, 0, 0, 0, kPaths}, whole_sums, whole);
    SplatList parts(w, h);
    TileSums part_sums(PixelRect{});
    for (const auto& [begin, end] : {std::pair<uint64_t, uint64_t>{0, 1},
                                     {1, 1023},
                                     {1023, 5000},
                                     {5000, 5001},
                                     {5001, kPaths}}) {
        SplatList part(w, h);
        s.renderer->Render({PixelRect{}, 0, 0, begin, end}, part_sums, part);
        parts += part;
    }
    EXPECT_GT(whole.entries().size(), 100u);
    EXPECT_EQ(whole.entries(), parts.entries());
    EXPECT_EQ(whole_sums.stats.samples, kPaths);
    EXPECT_EQ(part_sums.stats.samples, kPaths);
    EXPECT_EQ(whole_sums.stats.rays, part_sums.stats.rays);
    EXPECT_EQ(whole_sums.stats.invalid_samples, part_sums.stats.invalid_samples);
}

TEST(LightTracer, CancelledRenderStopsEarly) {
    const Scene scene = LoadTestScene("cornell_box.json", 16);
    const testing::SplatSetup s = testing::MakeSplatSetup(scene, "light", Unlimited());
    std::atomic<bool> cancel{true};
    SplatList splats(16, 16);
    TileSums sums(PixelRect{});
    s.renderer->Render({PixelRect{}, 0, 0, 0, 1 << 20}, sums, splats, &cancel);
    EXPECT_EQ(sums.stats.samples, 0u);
    EXPECT_TRUE(splats.entries().empty());
}

// The estimate of a block of pixels (the average of R, G and B over it) and its variance.
struct BlockEstimate {
    double mean = 0, variance = 0;
};

constexpr int kBlock = 8;

// The path tracer's blocks, their variances from each pixel's halves: (A - B)^2 / 4 estimates
// the variance of a pixel's mean, and pixels are independent.
std::vector<BlockEstimate> PathBlocks(const Image& image) {
    const int bw = image.width() / kBlock, bh = image.height() / kBlock;
    std::vector<BlockEstimate> blocks(size_t(bw * bh));
    for (int y = 0; y < bh * kBlock; ++y) {
        for (int x = 0; x < bw * kBlock; ++x) {
            BlockEstimate& b = blocks[size_t((y / kBlock) * bw + x / kBlock)];
            const double a = image.Pixel(x, y, "A.").Average();
            const double c = image.Pixel(x, y, "B.").Average();
            const double n = kBlock * kBlock;
            b.mean += image.Pixel(x, y).Average() / n;
            b.variance += (a - c) * (a - c) / 4 / (n * n);
        }
    }
    return blocks;
}

// The light tracer's blocks from `batches` independent ranges of light paths: a light path
// splats into several pixels of a block, so pixels are not independent; the batch means are.
std::vector<BlockEstimate> LightBlocks(const testing::SplatSetup& s, int batches,
                                       uint64_t paths_per_batch) {
    const int bw = s.camera->width() / kBlock, bh = s.camera->height() / kBlock;
    std::vector<std::vector<double>> per_batch(size_t(bw * bh));
    for (int k = 0; k < batches; ++k) {
        const uint64_t begin = uint64_t(k) * paths_per_batch;
        const Image image =
            testing::RenderSplatPaths(*s.renderer, *s.camera, begin, begin + paths_per_batch).image;
        std::vector<double> sums(per_batch.size(), 0.0);
        for (int y = 0; y < bh * kBlock; ++y) {
            for (int x = 0; x < bw * kBlock; ++x) {
                sums[size_t((y / kBlock) * bw + x / kBlock)] +=
                    image.Pixel(x, y).Average() / (kBlock * kBlock);
            }
        }
        for (size_t b = 0; b < sums.size(); ++b) per_batch[b].push_back(sums[b]);
    }
    std::vector<BlockEstimate> blocks(per_batch.size());
    for (size_t b = 0; b < blocks.size(); ++b) {
        double mean = 0, var = 0;
        for (double m : per_batch[b]) mean += m / batches;
        for (double m : per_batch[b]) var += (m - mean) * (m - mean) / (batches - 1);
        blocks[b] = {mean, var / batches};
    }
    return blocks;
}

// Blocks where some pixel sees a mirror or glass first: the light tracer cannot connect a delta
// vertex to the camera, so what is seen in them (E S+ ... paths) is the path tracer's alone.
std::vector<bool> SpecularBlocks(const EmbreeScene& es, const Camera& camera) {
    const int bw = camera.width() / kBlock, bh = camera.height() / kBlock;
    std::vector<bool> specular(size_t(bw * bh), false);
    constexpr int kGrid = 4;
    for (int y = 0; y < bh * kBlock; ++y) {
        for (int x = 0; x < bw * kBlock; ++x) {
            for (int j = 0; j < kGrid * kGrid; ++j) {
                const Ray ray = camera.GenerateRay(x, y, (j % kGrid + 0.5f) / kGrid,
                                                   (j / kGrid + 0.5f) / kGrid);
                const std::optional<SurfaceHit> hit = es.Intersect(ray);
                if (!hit) continue;
                const Material::Type type = es.scene().materials[size_t(hit->material)].type;
                if (type == Material::Type::kMirror || type == Material::Type::kDielectric) {
                    specular[size_t((y / kBlock) * bw + x / kBlock)] = true;
                }
            }
        }
    }
    return specular;
}

// Light tracing and path tracing at the same max_depth agree block by block (8x8 pixels) within
// their variances: each block's z with a Bonferroni threshold over the blocks, and the mean z
// (a bias common to all blocks) within its own.
void ExpectLightMatchesPath(const Scene& scene, const char* scene_name, int max_depth, uint64_t spp,
                            int batches, uint64_t paths_per_batch) {
    SplatRenderSettings settings;
    settings.max_depth = max_depth;
    settings.seed = 3;
    const testing::SplatSetup s = testing::MakeSplatSetup(scene, "light", settings);
    const std::vector<BlockEstimate> light = LightBlocks(s, batches, paths_per_batch);
    const std::vector<BlockEstimate> path =
        PathBlocks(testing::RenderPath(scene, spp, max_depth, 5).out.image);
    const std::vector<bool> specular = SpecularBlocks(*s.embree, *s.camera);
    int compared = 0;
    for (bool b : specular) compared += b ? 0 : 1;
    ASSERT_GT(compared, int(specular.size()) / 2);
    const double threshold = BonferroniZ(compared);
    double z_sum = 0, worst = 0;
    for (size_t b = 0; b < light.size(); ++b) {
        if (specular[b]) continue;
        const double se = std::sqrt(light[b].variance + path[b].variance);
        if (se == 0) {  // nothing there (the sky): both exactly black
            EXPECT_EQ(light[b].mean, path[b].mean) << scene_name << " block " << b;
            --compared;
            continue;
        }
        const double z = (light[b].mean - path[b].mean) / se;
        z_sum += z;
        worst = std::max(worst, std::abs(z));
        EXPECT_LT(std::abs(z), threshold)
            << scene_name << " block " << b << ": light " << light[b].mean << " +- "
            << std::sqrt(light[b].variance) << ", path " << path[b].mean << " +- "
            << std::sqrt(path[b].variance);
        // Noise small enough for the comparison to mean something: 5 % of the block.
        EXPECT_LT(se, 0.05 * path[b].mean + 1e-3) << scene_name << " block " << b;
    }
    const double mean_z = z_sum / std::sqrt(double(compared));
    std::printf(
        "[light] %s: %d blocks of %zu compared, largest |z| %.2f (threshold %.2f), "
        "sum z / sqrt(n) %.2f\n",
        scene_name, compared, light.size(), worst, threshold, mean_z);
    EXPECT_LT(std::abs(mean_z), BonferroniZ(1));
}

TEST(LightTracer, MatchesPathTracerOnCornellBox) {
    ExpectLightMatchesPath(LoadTestScene("cornell_box.json", 32), "cornell_box.json", 3, 256, 64,
                           32 * 32 * 256 / 64);
}

// The glass sphere's caustic on the floor, the mirror's, the glossy box and plastic sphere; the
// blocks that see the mirror or the glass are left out (see SpecularBlocks).
TEST(LightTracer, MatchesPathTracerOnMaterials) {
    ExpectLightMatchesPath(LoadTestScene("materials.json", 48), "materials.json", 5, 256, 64,
                           48 * 48 * 256 / 64);
}

// An emissive sphere inside a glass sphere over a diffuse floor. Light leaving the glass is
// radiance scaled by ior^2, which importance transport must not apply to a light path's flux:
// with the path tracer's radiance BSDF the light tracer's floor would be 2.25 times too bright.
TEST(LightTracer, MatchesPathTracerForALightInsideGlass) {
    Scene scene;
    Material floor;
    floor.reflectance = Rgb(0.8f, 0.7f, 0.6f);
    scene.materials.push_back(floor);
    Material glass;
    glass.type = Material::Type::kDielectric;
    glass.ior = 1.5f;
    scene.materials.push_back(glass);
    Material lamp;
    lamp.reflectance = Rgb(0.0f);
    lamp.emission = Rgb(2.0f, 1.5f, 1.0f);
    scene.materials.push_back(lamp);
    TriangleMesh quad;
    quad.material = 0;
    quad.positions = {{-4, 0, -4}, {-4, 0, 4}, {4, 0, 4}, {4, 0, -4}};  // normal +y
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(quad);
    scene.spheres.push_back({"glass", 1, Vec3d(0, 1.2, 0), 1});
    scene.spheres.push_back({"lamp", 2, Vec3d(0, 1.2, 0), 0.5});
    scene.camera = testing::SquareCamera({0, 4, 5}, {0, 0.3, 0}, {0, 1, 0}, 50, 32);
    ExpectLightMatchesPath(scene, "lamp in glass", 4, 256, 64, 32 * 32 * 256 / 64);
}

TEST(SplatRendererFactory, BuildsLightAndRefusesWhatItCannot) {
    auto is_splat_method = [](Method m) { return Info(m).work == WorkKind::kSplatPasses; };
    EXPECT_TRUE(is_splat_method(Method::kLight));
    EXPECT_TRUE(is_splat_method(Method::kBdpt));
    EXPECT_TRUE(is_splat_method(Method::kPpm));
    EXPECT_FALSE(is_splat_method(Method::kPath));
    EXPECT_FALSE(is_splat_method(Method::kWhitted));
    Scene scene = testing::PointLitFurnaceSphere(8);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const Camera camera(scene.camera, (*es)->origin());
    EXPECT_TRUE(MakeSplatRenderer(Method::kLight, **es, camera, {}).ok());
    EXPECT_TRUE(MakeSplatRenderer(Method::kPpm, **es, camera, {}).ok());
    SplatRenderSettings bad_alpha;
    bad_alpha.alpha = 1;
    EXPECT_EQ(MakeSplatRenderer(Method::kPpm, **es, camera, bad_alpha).status().code(),
              absl::StatusCode::kInvalidArgument);
    const auto path = MakeSplatRenderer(Method::kPath, **es, camera, {});
    EXPECT_EQ(path.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(path.status().message().find("path"), std::string::npos);

    scene.camera.filter = {PixelFilter::Type::kGaussian, 2};
    const Camera gaussian(scene.camera, (*es)->origin());
    const auto refused = MakeSplatRenderer(Method::kLight, **es, gaussian, {});
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(refused.status().message().find("light"), std::string::npos);
    EXPECT_NE(refused.status().message().find("gaussian"), std::string::npos);
    // Photons are gathered at filter-importance-sampled camera samples: any filter.
    EXPECT_TRUE(MakeSplatRenderer(Method::kPpm, **es, gaussian, {}).ok());
}

}  // namespace
}  // namespace lf
