// Every sample is a pure function of (seed, pixel, sample index): tiles, passes and threads
// must not change a single bit.
#include <gtest/gtest.h>

#include <tuple>

#include "lf/core/aov.h"
#include "lf/core/camera.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/local_executor.h"
#include "test_scenes.h"

namespace lf {
namespace {

class Determinism : public ::testing::Test {
  protected:
    void SetUp() override {
        scene_ = testing::MakeFurnace(1.0, Vec3d(), 0.7f, 1.0f, 24);
        // A sphere and a glossy box face so several BSDFs and light kinds are involved.
        Material glossy;
        glossy.type = Material::Type::kGlossy;
        glossy.roughness = 0.3f;
        glossy.reflectance = Rgb(0.9f);
        scene_.materials.push_back(glossy);
        scene_.meshes[3].material = 1;
        scene_.spheres.push_back({"ball", 0, Vec3d(0.4, -0.5, 0.6), 0.3});
        scene_.point_lights.push_back({Vec3d(0, 0.8, 0), Rgb(2.0f)});
        auto es = EmbreeScene::Build(scene_);
        ASSERT_TRUE(es.ok()) << es.status();
        embree_ = std::move(*es);
        camera_ = std::make_unique<Camera>(scene_.camera, embree_->origin());
        tracer_ = std::make_unique<PathTracer>(*embree_, -1);
        CameraSpec filtered = scene_.camera;
        filtered.filter = {PixelFilter::Type::kGaussian, 3};
        gaussian_camera_ = std::make_unique<Camera>(filtered, embree_->origin());
    }

    // `extras`: every AOV, a gaussian filter 3 px wide and a clamp of 1.5.
    Image Render(int tile, int threads, int passes, bool extras = false,
                 SamplerType sampler = defaults::kSampler) const {
        RenderSettings s;
        s.sampler = sampler;
        s.spp = 6;
        s.seed = 42;
        s.tile = tile;
        s.threads = threads;
        s.passes = passes;
        if (extras) {
            s.aovs = kAllAovs;
            s.clamp = 1.5;
        }
        return RenderImage(extras ? *gaussian_camera_ : *camera_, *tracer_, s).value().image;
    }

    Scene scene_;
    std::unique_ptr<EmbreeScene> embree_;
    std::unique_ptr<Camera> camera_;
    std::unique_ptr<PathTracer> tracer_;
    std::unique_ptr<Camera> gaussian_camera_;
};

// Both samplers: Sobol's sample s is point s/2 of the pixel's half s%2, so passes that start
// at odd samples (6 spp in 4 passes: [0,1) [1,3) [3,4) [4,6)) must continue both halves.
TEST_F(Determinism, SameBitsForAnyTileSizePassesAndThreadCount) {
    for (const SamplerType sampler : {SamplerType::kSobol, SamplerType::kIndependent}) {
        const Image reference = Render(24, 1, 1, false, sampler);
        for (auto [tile, threads, passes] :
             {std::tuple{1, 2, 1}, {5, 2, 3}, {7, 1, 2}, {16, 2, 6}, {64, 2, 4}}) {
            const Image other = Render(tile, threads, passes, false, sampler);
            for (const auto& [name, data] : reference.channels()) {
                EXPECT_EQ(data, *other.FindChannel(name))
                    << name << " tile " << tile << " " << SamplerTypeName(sampler);
            }
        }
    }
}

// The setting reaches the kernel: the two samplers' images are the same scene's, not the same
// bits.
TEST_F(Determinism, TheSamplerChangesTheNoise) {
    EXPECT_NE(*Render(24, 1, 1, false, SamplerType::kSobol).FindChannel("R"),
              *Render(24, 1, 1, false, SamplerType::kIndependent).FindChannel("R"));
}

TEST_F(Determinism, AovsFiltersAndClampKeepTheBitsForAnyTileSizePassesAndThreadCount) {
    const Image reference = Render(24, 1, 1, true);
    ASSERT_NE(reference.FindChannel("depth.Z"), nullptr);
    for (auto [tile, threads, passes] : {std::tuple{1, 2, 1}, {7, 1, 2}, {16, 2, 6}}) {
        const Image other = Render(tile, threads, passes, true);
        ASSERT_EQ(other.channels().size(), reference.channels().size());
        for (const auto& [name, data] : reference.channels()) {
            EXPECT_EQ(data, *other.FindChannel(name)) << name << " tile " << tile;
        }
    }
    // The filter moves samples, so the image differs from the box-filtered one.
    EXPECT_NE(*reference.FindChannel("R"), *Render(24, 1, 1).FindChannel("R"));
}

TEST_F(Determinism, SamplePassesAddUpToTheSameBits) {
    const PixelRect rect{3, 5, 9, 7};
    for (const SampleOptions options :
         {SampleOptions{}, SampleOptions{2.0, kAllAovs}, SampleOptions{0, 0, SamplerType::kSobol},
          SampleOptions{2.0, kAllAovs, SamplerType::kSobol}}) {
        const TileSums whole = RenderTile(*gaussian_camera_, *tracer_, rect, 9, 0, 8, options);
        TileSums parts = RenderTile(*gaussian_camera_, *tracer_, rect, 9, 5, 8, options);
        parts += RenderTile(*gaussian_camera_, *tracer_, rect, 9, 0, 2, options);
        parts += RenderTile(*gaussian_camera_, *tracer_, rect, 9, 2, 5, options);
        ASSERT_EQ(whole.aov_pixels.size(), parts.aov_pixels.size());
        for (size_t i = 0; i < whole.pixels.size(); ++i) {
            EXPECT_EQ(whole.pixels[i].Count(), parts.pixels[i].Count());
            for (int h = 0; h < 2; ++h) {
                for (int c = 0; c < 3; ++c) {
                    EXPECT_EQ(whole.pixels[i].sum[h][c], parts.pixels[i].sum[h][c]);
                }
            }
            if (options.aovs != 0) {
                EXPECT_EQ(whole.aov_pixels[i], parts.aov_pixels[i]);
            }
        }
    }
}

TEST_F(Determinism, DifferentSeedsGiveDifferentNoise) {
    RenderSettings s;
    s.spp = 2;
    s.seed = 1;
    const Image a = RenderImage(*camera_, *tracer_, s).value().image;
    s.seed = 2;
    const Image b = RenderImage(*camera_, *tracer_, s).value().image;
    EXPECT_NE(*a.FindChannel("R"), *b.FindChannel("R"));
}

}  // namespace
}  // namespace lf
