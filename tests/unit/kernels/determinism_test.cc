// Every sample is a pure function of (seed, pixel, sample index): tiles, passes and threads
// must not change a single bit.
#include <gtest/gtest.h>

#include <tuple>

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
    }

    Image Render(int tile, int threads, int passes) const {
        RenderSettings s;
        s.spp = 6;
        s.seed = 42;
        s.tile = tile;
        s.threads = threads;
        s.passes = passes;
        return RenderImage(*camera_, *tracer_, s).value().image;
    }

    Scene scene_;
    std::unique_ptr<EmbreeScene> embree_;
    std::unique_ptr<Camera> camera_;
    std::unique_ptr<PathTracer> tracer_;
};

TEST_F(Determinism, SameBitsForAnyTileSizePassesAndThreadCount) {
    const Image reference = Render(24, 1, 1);
    for (auto [tile, threads, passes] :
         {std::tuple{1, 2, 1}, {5, 2, 3}, {7, 1, 2}, {16, 2, 6}, {64, 2, 4}}) {
        const Image other = Render(tile, threads, passes);
        for (const auto& [name, data] : reference.channels()) {
            EXPECT_EQ(data, *other.FindChannel(name)) << name << " tile " << tile;
        }
    }
}

TEST_F(Determinism, SamplePassesAddUpToTheSameBits) {
    const PixelRect rect{3, 5, 9, 7};
    const TileSums whole = RenderTile(*camera_, *tracer_, rect, 9, 0, 8);
    TileSums parts = RenderTile(*camera_, *tracer_, rect, 9, 5, 8);
    parts += RenderTile(*camera_, *tracer_, rect, 9, 0, 2);
    parts += RenderTile(*camera_, *tracer_, rect, 9, 2, 5);
    for (size_t i = 0; i < whole.pixels.size(); ++i) {
        EXPECT_EQ(whole.pixels[i].Count(), parts.pixels[i].Count());
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(whole.pixels[i].sum[h][c], parts.pixels[i].sum[h][c]);
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
