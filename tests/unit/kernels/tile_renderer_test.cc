#include "lf/kernels/tile_renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"
#include "test_scenes.h"

namespace lf {
namespace {

// Returns NaN for every third sample index, +inf for every fifth, else the sample index.
class PoisonedEstimator : public RadianceEstimator {
  public:
    PoisonedEstimator() : geometry_(EmbreeScene::Build(empty_).value()) {}
    const EmbreeScene& geometry() const override { return *geometry_; }
    Rgb Li(const Ray&, Sampler& sampler, RenderStats& stats) const override {
        ++stats.rays;
        const uint64_t s = uint64_t(sampler.Get1D() * 1e6);
        if (s % 3 == 0) return Rgb(std::numeric_limits<float>::quiet_NaN());
        if (s % 5 == 0) return Rgb(std::numeric_limits<float>::infinity(), 0.0f, 0.0f);
        return Rgb(1.0f);
    }

  private:
    Scene empty_;
    std::unique_ptr<EmbreeScene> geometry_;
};

CameraSpec SmallCamera() {
    CameraSpec spec;
    spec.width = 7;
    spec.height = 5;
    return spec;
}

TEST(RenderTile, NonFiniteSamplesAreCountedAndNeverWritten) {
    const Camera camera(SmallCamera(), Vec3d());
    const PoisonedEstimator estimator;
    RenderSettings settings;
    settings.spp = 32;
    const RenderOutput out = RenderImage(camera, estimator, settings).value();
    EXPECT_GT(out.stats.invalid_samples, 0u);
    EXPECT_LT(out.stats.invalid_samples, out.stats.samples);
    EXPECT_EQ(out.stats.samples, 7u * 5u * 32u);
    for (const auto& [name, data] : out.image.channels()) {
        for (float v : data) EXPECT_TRUE(std::isfinite(v)) << name;
    }
    // Invalid samples count as zero, so the mean is the fraction of valid ones.
    double mean = 0;
    for (float v : *out.image.FindChannel("G")) mean += v;
    mean /= 35;
    EXPECT_NEAR(mean, 1.0 - double(out.stats.invalid_samples) / double(out.stats.samples), 1e-6);
}

TEST(RenderTile, CancelStopsWork) {
    const Camera camera(SmallCamera(), Vec3d());
    const PoisonedEstimator estimator;
    std::atomic<bool> cancel{true};
    const TileSums tile = RenderTile(camera, estimator, {0, 0, 7, 5}, 0, 0, 8, {}, &cancel);
    EXPECT_EQ(tile.stats.rays, 0u);
    EXPECT_EQ(tile.stats.samples, 0u);
}

// The box filter places sample s of pixel (x, y) at its sampler's first two numbers, exactly as
// the tile renderer did before filters: the sums of a tile are those of that loop, bit for bit.
TEST(RenderTile, BoxFilterKeepsTheBitsOfThePixelSquareSamples) {
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.6f, 1.0f, 10);
    scene.spheres.push_back({"ball", 0, Vec3d(0.4, -0.5, 0.6), 0.3});
    const std::unique_ptr<EmbreeScene> embree = EmbreeScene::Build(scene).value();
    const Camera camera(scene.camera, embree->origin());
    const PathTracer tracer(*embree, -1);
    const PixelRect rect{2, 3, 5, 4};
    const TileSums tile = RenderTile(camera, tracer, rect, 7, 0, 6);
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
        for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
            PixelSums expected;
            RenderStats stats;
            for (uint64_t s = 0; s < 6; ++s) {
                Sampler sampler(7, x, y, s);
                const Vec2 film = sampler.Get2D();
                expected.Add(s,
                             tracer.Li(camera.GenerateRay(x, y, film.x, film.y), sampler, stats));
            }
            for (int h = 0; h < 2; ++h) {
                for (int c = 0; c < 3; ++c) EXPECT_EQ(tile.at(x, y).sum[h][c], expected.sum[h][c]);
            }
        }
    }
}

// An emitter of radiance 1 filling the right half of the view (from film x = width/2 on) and
// nothing on the left: every sample is 0 or 1, and a pixel's mean estimates the chance that its
// sample lands right of the edge. With the box filter that is a step at the edge; with a gaussian
// of width w it is the truncated normal's CDF (sigma = w/6) at the pixel centre's distance from the
// edge. Each column's mean over its rows is compared within 5 binomial standard errors.
TEST(RenderTile, GaussianFilterBlursAnEdgeByItsCdf) {
    constexpr int kSize = 32, kSpp = 64;
    Scene scene;
    Material emitter;
    emitter.reflectance = Rgb(0.0f);
    emitter.emission = Rgb(1.0f);
    scene.materials.push_back(emitter);
    TriangleMesh half;
    // x <= 0, which is the right of the view: the camera's right is forward x up = -x.
    half.positions = {{0, -10, 0}, {-10, -10, 0}, {-10, 10, 0}, {0, 10, 0}};
    half.triangles = {{0, 1, 2}, {0, 2, 3}};  // front face towards the camera at -z
    scene.meshes.push_back(half);
    scene.camera = testing::SquareCamera({0, 0, -1}, {0, 0, 0}, {0, 1, 0}, 60, kSize);
    const std::unique_ptr<EmbreeScene> embree = EmbreeScene::Build(scene).value();
    const PathTracer tracer(*embree, -1);
    for (const double width : {0.0, 4.0}) {
        CameraSpec spec = scene.camera;
        if (width > 0) spec.filter = {PixelFilter::Type::kGaussian, width};
        const Camera camera(spec, embree->origin());
        const TileSums tile = RenderTile(camera, tracer, {0, 0, kSize, kSize}, 3, 0, kSpp);
        for (int x = 0; x < kSize; ++x) {
            double sum = 0;
            for (int y = 0; y < kSize; ++y) sum += tile.at(x, y).Mean().g;
            const double mean = sum / kSize;
            // The pixel centre's film x is x + 0.5; the edge is at kSize / 2.
            const double d = x + 0.5 - kSize / 2;
            double expected = d > 0 ? 1 : 0;
            if (width > 0) {
                const double s = width / 6 * std::sqrt(2.0), edge = std::erf(width / 2 / s);
                expected = std::clamp((std::erf(d / s) + edge) / (2 * edge), 0.0, 1.0);
            }
            const double n = double(kSize) * kSpp;
            const double tolerance = 5 * std::sqrt(expected * (1 - expected) / n) + 1e-6;
            EXPECT_NEAR(mean, expected, tolerance) << "width " << width << " column " << x;
        }
    }
}

}  // namespace
}  // namespace lf
