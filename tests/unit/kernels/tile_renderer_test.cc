#include "lf/kernels/tile_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "lf/local/local_executor.h"

namespace lf {
namespace {

// Returns NaN for every third sample index, +inf for every fifth, else the sample index.
class PoisonedEstimator : public RadianceEstimator {
  public:
    Rgb Li(const Ray&, Sampler& sampler, RenderStats& stats) const override {
        ++stats.rays;
        const uint64_t s = uint64_t(sampler.Get1D() * 1e6);
        if (s % 3 == 0) return Rgb(std::numeric_limits<float>::quiet_NaN());
        if (s % 5 == 0) return Rgb(std::numeric_limits<float>::infinity(), 0.0f, 0.0f);
        return Rgb(1.0f);
    }
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
    const TileSums tile = RenderTile(camera, estimator, {0, 0, 7, 5}, 0, 0, 8, &cancel);
    EXPECT_EQ(tile.stats.rays, 0u);
    EXPECT_EQ(tile.stats.samples, 0u);
}

}  // namespace
}  // namespace lf
