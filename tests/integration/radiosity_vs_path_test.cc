// Radiosity against the path tracer on the Cornell box at 64 x 64. Both renderers estimate the
// same pixel integrals from the same film positions (same seed and sample count), so they may
// differ only by the path tracer's noise and radiosity's discretisation, and the latter must
// shrink as the mesh refines.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "lf/core/camera.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/scene_loader.h"
#include "lf/job/method_registry.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/local_executor.h"

namespace lf {
namespace {

constexpr int kResolution = 64;
constexpr int kBlock = 8;
constexpr uint64_t kSpp = 512;
constexpr uint64_t kSeed = 7;
// A correct pair of renderers fails a 5-sigma check with probability below 1e-6 per region.
constexpr double kSigmas = 5;

// Per region and channel: the mean over the region's pixels and its standard error from the
// pixels' half-sample estimates, Var(pixel mean) ≈ (A - B)^2 / 4.
struct RegionMeans {
    std::vector<double> mean, error;  // [region * 3 + channel]
};

RegionMeans Means(const Image& image, const std::vector<int>& region, int regions) {
    RegionMeans r;
    r.mean.assign(size_t(regions) * 3, 0);
    r.error.assign(r.mean.size(), 0);
    std::vector<double> count(size_t(regions), 0);
    for (int g : region) {
        if (g >= 0) count[size_t(g)] += 1;
    }
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        const std::vector<float>& v = *image.FindChannel(names[c]);
        const std::vector<float>& a = *image.FindChannel(std::string("A.") + names[c]);
        const std::vector<float>& b = *image.FindChannel(std::string("B.") + names[c]);
        for (size_t p = 0; p < region.size(); ++p) {
            if (region[p] < 0) continue;
            const double n = count[size_t(region[p])];
            const size_t k = size_t(region[p]) * 3 + size_t(c);
            r.mean[k] += v[p] / n;
            r.error[k] += (double(a[p]) - b[p]) * (double(a[p]) - b[p]) / 4 / (n * n);
        }
    }
    for (double& e : r.error) e = std::sqrt(e);
    return r;
}

// Radiosity's difference from the path tracer over regions: the mean squared difference is
// discretisation^2 + noise^2, so subtracting the noise leaves radiosity's own error.
struct Difference {
    double rms = 0, noise = 0, debiased = 0;
};

Difference Compare(const RegionMeans& radiosity, const RegionMeans& path) {
    double diff2 = 0, noise2 = 0;
    for (size_t k = 0; k < path.mean.size(); ++k) {
        const double d = radiosity.mean[k] - path.mean[k];
        diff2 += d * d;
        noise2 += path.error[k] * path.error[k];
    }
    const double m = double(path.mean.size());
    return {std::sqrt(diff2 / m), std::sqrt(noise2 / m),
            std::sqrt(std::max(0.0, diff2 - noise2) / m)};
}

// 8 x 8-pixel blocks.
std::vector<int> Blocks() {
    std::vector<int> region(kResolution * kResolution);
    for (int y = 0; y < kResolution; ++y) {
        for (int x = 0; x < kResolution; ++x) {
            region[size_t(y) * kResolution + x] =
                (y / kBlock) * (kResolution / kBlock) + x / kBlock;
        }
    }
    return region;
}

// Walls and box faces: the pixels whose centre and corners all see one scene mesh.
std::vector<int> Surfaces(const EmbreeScene& scene, const Camera& camera) {
    std::vector<int> region(kResolution * kResolution, -1);
    for (int y = 0; y < kResolution; ++y) {
        for (int x = 0; x < kResolution; ++x) {
            int mesh = -2;
            for (float u : {0.0f, 0.5f, 0.999f}) {
                for (float v : {0.0f, 0.5f, 0.999f}) {
                    const auto hit = scene.Intersect(camera.GenerateRay(x, y, u, v));
                    const int m = hit ? hit->mesh : -1;
                    mesh = mesh == -2 || mesh == m ? m : -1;
                }
            }
            region[size_t(y) * kResolution + x] = mesh;
        }
    }
    return region;
}

// A scene of tests/scenes at 64 x 64 and its path-traced reference.
class RadiosityVsPath : public ::testing::Test {
  protected:
    // `edit` changes the scene before both methods render it.
    void Load(const std::string& file, void (*edit)(Scene&) = nullptr) {
        auto loaded = LoadScene(std::string(LF_TEST_SCENES) + "/" + file);
        ASSERT_TRUE(loaded.ok()) << loaded.status();
        scene_ = std::move(*loaded);
        scene_.camera.width = scene_.camera.height = kResolution;
        if (edit) edit(scene_);
        auto es = EmbreeScene::Build(scene_);
        ASSERT_TRUE(es.ok()) << es.status();
        embree_ = std::move(*es);
        camera_ = std::make_unique<Camera>(scene_.camera, embree_->origin());
        settings_.spp = kSpp;
        settings_.seed = kSeed;
        path_ = RenderImage(*camera_, PathTracer(*embree_, -1), settings_).value().image;
    }

    Scene scene_;
    std::unique_ptr<EmbreeScene> embree_;
    std::unique_ptr<Camera> camera_;
    RenderSettings settings_;
    Image path_;
};

TEST_F(RadiosityVsPath, CornellBoxAgreesAndConvergesWithTheMesh) {
    ASSERT_NO_FATAL_FAILURE(Load("cornell_box.json"));
    const Scene* scene = &scene_;
    const EmbreeScene& embree = *embree_;
    const Camera& camera = *camera_;
    const RenderSettings& settings = settings_;
    const Image& path = path_;

    const std::vector<int> blocks = Blocks(), surfaces = Surfaces(embree, camera);
    const int block_count = (kResolution / kBlock) * (kResolution / kBlock);
    const int surface_count = int(scene->meshes.size());
    const RegionMeans path_blocks = Means(path, blocks, block_count);
    const RegionMeans path_surfaces = Means(path, surfaces, surface_count);

    const int64_t patch_counts[] = {250, 1000, 4000};
    std::vector<RegionMeans> radiosity_blocks, radiosity_surfaces;
    std::vector<double> debiased;
    std::printf("%8s %10s %10s %10s   (block means; path-traced mean %.4f)\n", "patches",
                "rms diff", "noise", "debiased", [&] {
                    double s = 0;
                    for (double m : path_blocks.mean) s += m;
                    return s / double(path_blocks.mean.size());
                }());
    for (int64_t n : patch_counts) {
        RadiosityOptions options;
        options.patches = n;
        auto renderer = PrepareRadiosity(embree, options);
        ASSERT_TRUE(renderer.ok()) << renderer.status();
        const Image image = RenderImage(camera, **renderer, settings).value().image;
        radiosity_blocks.push_back(Means(image, blocks, block_count));
        radiosity_surfaces.push_back(Means(image, surfaces, surface_count));
        const Difference d = Compare(radiosity_blocks.back(), path_blocks);
        debiased.push_back(d.debiased);
        std::printf("%8ld %10.5f %10.5f %10.5f\n", n, d.rms, d.noise, d.debiased);
    }
    // The finer the mesh, the closer.
    EXPECT_GT(debiased[0], debiased[1]);
    EXPECT_GT(debiased[1], debiased[2]);

    // Surface by surface at 1000 patches (5 cm, half the light's width: from here the mesh
    // resolves the scene's features). Radiosity does not follow shadow and light boundaries, so
    // its error is O(h) there: e(h) ≈ 2 (R(h/2) - R(h)) (Richardson), and 4000 patches halve h.
    const RegionMeans& r = radiosity_surfaces[1];
    for (size_t k = 0; k < path_surfaces.mean.size(); ++k) {
        const double discretisation = 2 * std::abs(radiosity_surfaces[2].mean[k] - r.mean[k]);
        EXPECT_NEAR(r.mean[k], path_surfaces.mean[k],
                    kSigmas * path_surfaces.error[k] + discretisation)
            << scene->meshes[k / 3].name << " channel " << k % 3;
    }
}

// A white sphere on the Cornell box's floor, meshed as radiosity meshes it (PrepareSceneFor), so
// both methods see one geometry: surface by surface (the sphere's pixels one of them), radiosity
// is within 3 % of the path tracer plus its noise (5 sigma).
TEST_F(RadiosityVsPath, CornellBoxWithASphereAgreesSurfaceBySurface) {
    ASSERT_NO_FATAL_FAILURE(Load("cornell_box.json", [](Scene& scene) {
        int white = 0;
        while (scene.materials[size_t(white)].name != "white") ++white;
        scene.spheres.push_back({"ball", white, Vec3d(0.4, 0.07, 0.13), 0.07});
        PrepareSceneFor(Method::kRadiosity, scene);
    }));
    ASSERT_TRUE(scene_.spheres.empty());
    const int ball = int(scene_.meshes.size()) - 1;
    ASSERT_EQ(scene_.meshes[size_t(ball)].name, "ball");
    RadiosityOptions options;
    options.patches = 4000;
    auto renderer = PrepareRadiosity(*embree_, options);
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    const Image image = RenderImage(*camera_, **renderer, settings_).value().image;

    const std::vector<int> surfaces = Surfaces(*embree_, *camera_);
    const int count = int(scene_.meshes.size());
    EXPECT_GT(std::count(surfaces.begin(), surfaces.end(), ball), 50);
    const RegionMeans path = Means(path_, surfaces, count);
    const RegionMeans radiosity = Means(image, surfaces, count);
    for (size_t k = 0; k < path.mean.size(); ++k) {
        const double p = path.mean[k];
        if (p == 0) continue;  // a surface the camera does not see
        std::printf("%-12s %d radiosity / path %.4f\n", scene_.meshes[k / 3].name.c_str(),
                    int(k % 3), radiosity.mean[k] / p);
        EXPECT_NEAR(radiosity.mean[k], p, 0.03 * p + kSigmas * path.error[k])
            << scene_.meshes[k / 3].name << " channel " << k % 3;
    }
}

// Hierarchical radiosity on the 4000-patch Cornell box: at its default link error, surface by
// surface within 3 % of the path tracer plus its noise (5 sigma), as the flat method above (it is
// about 1-1.5 % darker than flat on the ceiling and the boxes: links that see part of a
// cluster); at a fine link error within 1 % of the flat solution on the same mesh, the links'
// own error, both seeing the same discretisation.
TEST_F(RadiosityVsPath, HierarchicalCornellBoxAgreesWithPathAndFlatSurfaceBySurface) {
    ASSERT_NO_FATAL_FAILURE(Load("cornell_box.json"));
    const std::vector<int> surfaces = Surfaces(*embree_, *camera_);
    const int count = int(scene_.meshes.size());
    const RegionMeans path = Means(path_, surfaces, count);
    RadiosityOptions options;
    options.patches = 4000;
    options.solver = RadiositySolver::kJacobi;
    const auto solve = [&](bool hierarchical, double link_error) {
        options.hierarchical = hierarchical;
        options.link_error = link_error;
        auto renderer = PrepareRadiosity(*embree_, options);
        EXPECT_TRUE(renderer.ok()) << renderer.status();
        if (hierarchical) EXPECT_GT((*renderer)->report().cluster_links, 0);
        return Means(RenderImage(*camera_, **renderer, settings_).value().image, surfaces, count);
    };
    const RegionMeans flat = solve(false, 0);
    const RegionMeans coarse = solve(true, RadiosityOptions().link_error);
    const RegionMeans fine = solve(true, 1e-5);
    for (size_t k = 0; k < path.mean.size(); ++k) {
        const double p = path.mean[k];
        if (p == 0) continue;  // a surface the camera does not see
        std::printf("%-12s %d default / path %.4f, fine / flat %.4f\n",
                    scene_.meshes[k / 3].name.c_str(), int(k % 3), coarse.mean[k] / p,
                    fine.mean[k] / flat.mean[k]);
        EXPECT_NEAR(coarse.mean[k], p, 0.03 * p + kSigmas * path.error[k])
            << scene_.meshes[k / 3].name << " channel " << k % 3;
        EXPECT_NEAR(fine.mean[k], flat.mean[k], 0.01 * flat.mean[k])
            << scene_.meshes[k / 3].name << " channel " << k % 3;
    }
}

// Refinement from 250 patches to a target of 0.1 against the uniform mesh of the same size:
// splitting where the solution varies must beat splitting everywhere. Both are compared with the
// path tracer as above (block means, noise subtracted), so the reference is unbiased.
void ExpectRefinementBeatsAUniformMeshOfTheSameSize(const EmbreeScene& embree, const Camera& camera,
                                                    const RenderSettings& settings,
                                                    const Image& path) {
    const std::vector<int> blocks = Blocks();
    const int block_count = (kResolution / kBlock) * (kResolution / kBlock);
    const RegionMeans path_blocks = Means(path, blocks, block_count);

    struct Result {
        int64_t patches = 0;
        double error = 0;
    };
    auto solve = [&](const RadiosityOptions& options) {
        const auto start = std::chrono::steady_clock::now();
        auto renderer = PrepareRadiosity(embree, options);
        EXPECT_TRUE(renderer.ok()) << renderer.status();
        if (!renderer.ok()) return Result{};
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const Image image = RenderImage(camera, **renderer, settings).value().image;
        const RadiosityReport& r = (*renderer)->report();
        const Result result{r.patches,
                            Compare(Means(image, blocks, block_count), path_blocks).debiased};
        std::printf(
            "%6ld patches (target %.2g, %zu passes): indicator max %.3f, mean %.4f; debiased "
            "block error %.5f; %.2f s\n",
            r.patches, options.target_error, r.refinement.size(), r.estimated_error,
            r.mean_estimated_error, result.error, seconds);
        return result;
    };
    RadiosityOptions coarse_options;
    coarse_options.patches = 250;
    const Result coarse = solve(coarse_options);
    RadiosityOptions refined_options = coarse_options;
    refined_options.target_error = 0.1;
    const Result refined = solve(refined_options);
    RadiosityOptions uniform_options;
    uniform_options.patches = refined.patches;
    const Result uniform = solve(uniform_options);

    EXPECT_GT(refined.patches, coarse.patches);
    EXPECT_LT(refined.error, coarse.error);
    EXPECT_LE(uniform.patches, refined.patches);
    EXPECT_LT(refined.error, uniform.error);
}

TEST_F(RadiosityVsPath, RefinementBeatsAUniformMeshOfTheSameSize) {
    ASSERT_NO_FATAL_FAILURE(Load("cornell_box.json"));
    ExpectRefinementBeatsAUniformMeshOfTheSameSize(*embree_, *camera_, settings_, path_);
}

// The Cornell box's light and boxes in a room three times as wide and deep
// (cornell_box_wide.json): the light falls off across the floor and walls, and refinement pays
// off more than in the box, where the error is spread over every wall (docs/radiosity.md).
TEST_F(RadiosityVsPath, RefinementBeatsAUniformMeshOfTheSameSizeUnderALocalLight) {
    ASSERT_NO_FATAL_FAILURE(Load("cornell_box_wide.json"));
    ExpectRefinementBeatsAUniformMeshOfTheSameSize(*embree_, *camera_, settings_, path_);
}

// Block regions, the floor's pixels split further by the checker texel they see (light or dark,
// from the hit's position on tests/scenes/radiosity/room.gltf's 0.5 m texels): region 2 b + 1
// holds block b's dark floor pixels, 2 b its other pixels. Pixels whose centre and corners do not
// all see one texel of the floor (or one other mesh) belong to no region.
std::vector<int> BlocksByTexel(const EmbreeScene& scene, const Camera& camera, int floor) {
    const std::vector<int> blocks = Blocks();
    std::vector<int> region(blocks.size(), -1);
    for (int y = 0; y < kResolution; ++y) {
        for (int x = 0; x < kResolution; ++x) {
            int kind = -2;  // -1: mixed; 2: a light floor texel, 3: a dark one; 10 + other meshes
            for (float u : {0.0f, 0.5f, 0.999f}) {
                for (float v : {0.0f, 0.5f, 0.999f}) {
                    const auto hit = scene.Intersect(camera.GenerateRay(x, y, u, v));
                    int k = -1;
                    if (hit && hit->mesh == floor) {
                        const Vec3d p = Vec3d(hit->p) + scene.origin();
                        const int ix = int(std::floor((p.x + 2) / 0.5));
                        const int iz = int(std::floor((2 - p.z) / 0.5));
                        k = (ix + iz) % 2 == 0 ? 2 : 3;
                    } else if (hit) {
                        k = 10 + hit->mesh;
                    }
                    kind = kind == -2 || kind == k ? k : -1;
                }
            }
            const size_t i = size_t(y) * kResolution + size_t(x);
            if (kind >= 0) region[i] = 2 * blocks[i] + (kind == 3 ? 1 : 0);
        }
    }
    return region;
}

// A textured glTF room as a modelling tool exports it (tests/scenes/radiosity): principled
// materials, a checker-textured floor, a meshed block, a point and a spot light. Radiosity keeps
// the diffuse parts and the texture detail: block by block, the floor's light and dark texels
// apart, within 3 % of the path tracer plus its noise (5 sigma).
TEST_F(RadiosityVsPath, TexturedGltfRoomAgreesBlockByBlock) {
    ASSERT_NO_FATAL_FAILURE(Load("radiosity/room.gltf"));
    EXPECT_EQ(RadiosityLimitation(scene_), "");
    EXPECT_EQ(RadiosityDrops(scene_), "specular reflection: \"white plaster\"");
    int floor = -1;
    for (size_t m = 0; m < scene_.meshes.size(); ++m) {
        if (scene_.meshes[m].name == "floor[0]") floor = int(m);
    }
    ASSERT_GE(floor, 0);
    RadiosityOptions options;
    options.patches = 4000;
    auto renderer = PrepareRadiosity(*embree_, options);
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    const Image image = RenderImage(*camera_, **renderer, settings_).value().image;

    const std::vector<int> region = BlocksByTexel(*embree_, *camera_, floor);
    const int regions = 2 * (kResolution / kBlock) * (kResolution / kBlock);
    std::vector<int> pixels(size_t(regions), 0);
    for (int r : region) {
        if (r >= 0) ++pixels[size_t(r)];
    }
    const RegionMeans path = Means(path_, region, regions);
    const RegionMeans radiosity = Means(image, region, regions);
    double light_floor = 0, dark_floor = 0, worst = 0;
    int compared = 0, light_n = 0, dark_n = 0;
    for (int r = 0; r < regions; ++r) {
        if (pixels[size_t(r)] < 8) continue;  // too few pixels to say much
        ++compared;
        for (int c = 0; c < 3; ++c) {
            const size_t k = size_t(r) * 3 + size_t(c);
            const double p = path.mean[k], e = path.error[k];
            worst = std::max(worst, (std::abs(radiosity.mean[k] - p) - kSigmas * e) / p);
            EXPECT_NEAR(radiosity.mean[k], p, 0.03 * p + kSigmas * e)
                << "block " << r / 2 << (r % 2 ? " dark texels" : "") << " channel " << c;
        }
    }
    // Radiosity over the path tracer in G per block: other pixels, then the dark floor texels.
    for (int by = 0; by < 8; ++by) {
        for (int bx = 0; bx < 8; ++bx) {
            const size_t k = size_t(2 * (by * 8 + bx)) * 3 + 1;
            std::printf("%6.3f", pixels[k / 3] >= 8 ? radiosity.mean[k] / path.mean[k] : 0.0);
        }
        std::printf("   ");
        for (int bx = 0; bx < 8; ++bx) {
            const size_t k = size_t(2 * (by * 8 + bx) + 1) * 3 + 1;
            std::printf("%6.3f", pixels[k / 3] >= 8 ? radiosity.mean[k] / path.mean[k] : 0.0);
        }
        std::printf("\n");
    }
    // The floor's texels, from the pixels of blocks that see only floor.
    for (int y = 0; y < kResolution; ++y) {
        for (int x = 0; x < kResolution; ++x) {
            const size_t i = size_t(y) * kResolution + size_t(x);
            const auto hit = embree_->Intersect(camera_->GenerateRay(x, y, 0.5f, 0.5f));
            if (region[i] < 0 || !hit || hit->mesh != floor) continue;
            const double g = (*image.FindChannel("G"))[i];
            (region[i] % 2 ? dark_floor : light_floor) += g;
            ++(region[i] % 2 ? dark_n : light_n);
        }
    }
    ASSERT_GT(light_n, 0);
    ASSERT_GT(dark_n, 0);
    std::printf("%d regions compared; worst excess over 5 sigma %.4f; floor light %.4f dark %.4f\n",
                compared, worst, light_floor / light_n, dark_floor / dark_n);
    // sRGB 200 and 60 are 0.578 and 0.0452 linear: the checker keeps its contrast of ~13.
    EXPECT_GT(light_floor / light_n, 6 * dark_floor / dark_n);
}

}  // namespace
}  // namespace lf
