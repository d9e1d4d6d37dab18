// Adaptive sampling (--target-error): every tile stops at the target, the image's own error
// estimate (from the A/B halves) agrees with its true error against an independent high-spp
// reference, the result is deterministic, and a time limit stops it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace lf {
namespace {

constexpr int kResolution = 64;
constexpr double kTarget = 0.05;
// The check of true against estimated error is a z-test on their per-pixel difference: a
// correct estimator fails it with probability 6e-5.
constexpr double kSigmas = 4;

// z with P(Z > z) = p for a standard normal Z, by bisection on erfc.
double InverseNormalTail(double p) {
    double lo = 0, hi = 40;
    for (int i = 0; i < 100; ++i) {
        const double mid = (lo + hi) / 2;
        (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
    }
    return lo;
}

class AdaptiveSampling : public ::testing::Test {
  protected:
    void SetUp() override {
        absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
        ASSERT_TRUE(scene.ok()) << scene.status();
        scene_ = *std::move(scene);
        scene_.camera.width = scene_.camera.height = kResolution;
        absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(scene_);
        ASSERT_TRUE(embree.ok()) << embree.status();
        embree_ = std::move(*embree);
        camera_ = std::make_unique<Camera>(scene_.camera, embree_->origin());
        tracer_ = std::make_unique<PathTracer>(*embree_, -1);
    }

    // `clock` empty: the real one.
    RenderOutput Adaptive(const AdaptiveSettings& adaptive, int threads = 2,
                          const RunClock& clock = {}, const ProgressFn& progress = {}) {
        RenderSettings settings;
        settings.spp = 8;
        settings.seed = 11;
        settings.threads = threads;
        settings.tile = 16;
        absl::StatusOr<RenderOutput> out =
            RenderImageAdaptive(*camera_, *tracer_, settings, adaptive, progress, clock);
        EXPECT_TRUE(out.ok()) << out.status();
        return *std::move(out);
    }

    // With a clock that stands still until `merges` passes have merged, then reads the limit
    // (0.3 s) passed: the time limit comes after that much work whatever the machine's load.
    RenderOutput TimeLimited(const AdaptiveSettings& adaptive, int merges) {
        const absl::Time t0 = absl::FromUnixSeconds(1000);
        std::atomic<int> merged{0};
        return Adaptive(
            adaptive, 2, [&] { return merged >= merges ? t0 + absl::Seconds(0.3) : t0; },
            [&](size_t, size_t) { ++merged; });
    }

    Scene scene_;  // the Embree scene refers to it
    std::unique_ptr<EmbreeScene> embree_;
    std::unique_ptr<Camera> camera_;
    std::unique_ptr<PathTracer> tracer_;
};

// Per pixel, mean over channels of a squared difference of two channel sets.
std::vector<double> SquaredDifference(const Image& x, const std::string& px, const Image& y,
                                      const std::string& py, double scale) {
    std::vector<double> d(size_t(x.width()) * x.height(), 0);
    for (const char* c : {"R", "G", "B"}) {
        const std::vector<float>& a = *x.FindChannel(px + c);
        const std::vector<float>& b = *y.FindChannel(py + c);
        for (size_t i = 0; i < d.size(); ++i) {
            const double diff = (double(a[i]) - b[i]) * scale;
            d[i] += diff * diff / 3;
        }
    }
    return d;
}

TEST_F(AdaptiveSampling, TrueErrorMatchesTheEstimate) {
    const RenderOutput out = Adaptive({.target_error = kTarget});
    EXPECT_EQ(out.adaptive.tiles_above_target, 0);
    EXPECT_LE(out.adaptive.worst_tile_error, kTarget);
    EXPECT_GT(out.adaptive.max_spp, out.adaptive.min_spp);  // tiles differ in difficulty

    RenderSettings settings;
    settings.spp = 2048;
    settings.seed = 12;  // independent of the adaptive render
    settings.threads = 2;
    absl::StatusOr<RenderOutput> reference = RenderImage(*camera_, *tracer_, settings);
    ASSERT_TRUE(reference.ok()) << reference.status();

    // E[(x - r)^2] = Var(x) + Var(r) for independent unbiased x and r; the half-buffer
    // estimates ((A - B) / 2)^2 of both variances are unbiased, so per pixel
    // D = (x - r)^2 - ((A - B) / 2)^2 - ((A_r - B_r) / 2)^2 has mean 0 if the estimate is right.
    const std::vector<double> truth = SquaredDifference(out.image, "", reference->image, "", 1);
    const std::vector<double> own = SquaredDifference(out.image, "A.", out.image, "B.", 0.5);
    const std::vector<double> ref_noise =
        SquaredDifference(reference->image, "A.", reference->image, "B.", 0.5);
    double sum = 0, sum2 = 0, true_mse = 0, estimated_mse = 0, ref_mse = 0, mean = 0;
    const double n = double(truth.size());
    for (size_t i = 0; i < truth.size(); ++i) {
        const double d = truth[i] - own[i] - ref_noise[i];
        sum += d;
        sum2 += d * d;
        true_mse += truth[i] / n;
        estimated_mse += own[i] / n;
        ref_mse += ref_noise[i] / n;
    }
    for (const char* c : {"R", "G", "B"}) {
        for (float v : *reference->image.FindChannel(c)) mean += v / (3 * n);
    }
    const double d_mean = sum / n;
    const double d_error = std::sqrt(std::max(0.0, sum2 / n - d_mean * d_mean) / (n - 1));
    EXPECT_LT(std::abs(d_mean), kSigmas * d_error)
        << "true MSE " << true_mse - ref_mse << " estimated " << estimated_mse;
    const double true_relative =
        std::sqrt(std::max(0.0, true_mse - ref_mse)) / (mean + kRelativeErrorFloor);
    std::printf(
        "target %.3f: estimated relative error %.4f, true %.4f (ratio %.3f), spp %llu..%llu,"
        " MSE difference %.3g +- %.3g\n",
        kTarget, out.adaptive.estimated_error, true_relative,
        true_relative / out.adaptive.estimated_error, (unsigned long long)out.adaptive.min_spp,
        (unsigned long long)out.adaptive.max_spp, d_mean, d_error);

    // Tile by tile: the same z-test on each tile's pixels, at a Bonferroni-corrected level so
    // the whole set of tiles fails a correct estimator with probability about 2e-4 (a normal
    // tail of 1e-4 / tiles on each side). And the true sqrt(relMSE), what the target bounds
    // (each pixel's squared error over its reference value squared + epsilon, channels
    // averaged), over the tile's own estimate: a tile's 256 pixels make either figure noisy by
    // some 10-20 %, so the median over tiles is checked against the band the estimate promises
    // (0.67-1.5x), not each tile.
    const double tiles = double(out.adaptive.per_tile.size());
    const double tile_sigmas = InverseNormalTail(1e-4 / tiles);
    std::vector<double> ratios, relative;
    for (const AdaptiveReport::Tile& tile : out.adaptive.per_tile) {
        double t = 0, e = 0, rel = 0, d_sum = 0, d_sum2 = 0;
        for (int y = tile.rect.y0; y < tile.rect.y0 + tile.rect.height; ++y) {
            for (int x = tile.rect.x0; x < tile.rect.x0 + tile.rect.width; ++x) {
                const size_t i = size_t(y) * kResolution + x;
                t += truth[i] - ref_noise[i];
                e += own[i];
                const double d = truth[i] - own[i] - ref_noise[i];
                d_sum += d;
                d_sum2 += d * d;
                for (const char* c : {"R", "G", "B"}) {
                    const double v = (*out.image.FindChannel(c))[i];
                    const double r = (*reference->image.FindChannel(c))[i];
                    const double h =
                        0.5 * ((*reference->image.FindChannel(std::string("A.") + c))[i] -
                               (*reference->image.FindChannel(std::string("B.") + c))[i]);
                    rel += ((v - r) * (v - r) - h * h) / (r * r + kRelativeErrorEpsilon) / 3;
                }
            }
        }
        const double m = double(tile.rect.Area());
        const double tile_mean = d_sum / m;
        const double tile_error =
            std::sqrt(std::max(0.0, d_sum2 / m - tile_mean * tile_mean) / (m - 1));
        EXPECT_LE(std::abs(tile_mean), tile_sigmas * tile_error)
            << "tile at (" << tile.rect.x0 << ", " << tile.rect.y0 << "): true MSE " << t / m
            << ", estimated " << e / m;
        if (e > 0) ratios.push_back(std::sqrt(std::max(0.0, t) / e));
        relative.push_back(std::sqrt(std::max(0.0, rel / m)) / tile.error);
    }
    std::sort(ratios.begin(), ratios.end());
    std::sort(relative.begin(), relative.end());
    std::printf("per tile true / estimated: min %.2f, median %.2f, max %.2f over %zu tiles\n",
                ratios.front(), ratios[ratios.size() / 2], ratios.back(), ratios.size());
    std::printf(
        "per tile true sqrt(relMSE) / estimated: min %.2f, median %.2f, max %.2f (target %.3f)\n",
        relative.front(), relative[relative.size() / 2], relative.back(), kTarget);
    EXPECT_GE(relative[relative.size() / 2], 0.67);
    EXPECT_LE(relative[relative.size() / 2], 1.5);
}

TEST_F(AdaptiveSampling, IsDeterministicForAnyThreadCount) {
    const AdaptiveSettings adaptive{.target_error = 0.1};
    const RenderOutput one = Adaptive(adaptive, 1), two = Adaptive(adaptive, 2);
    for (const char* c : {"R", "A.G", "B.B", "spp"}) {
        EXPECT_EQ(*one.image.FindChannel(c), *two.image.FindChannel(c)) << c;
    }
}

TEST_F(AdaptiveSampling, TimeLimitStopsSampling) {
    const RenderOutput out = TimeLimited({.target_error = 1e-4, .time_limit = 0.3}, 24);
    EXPECT_TRUE(out.adaptive.timed_out);
    EXPECT_GT(out.adaptive.tiles_above_target, 0);
    // The first passes, then passes cut at the limit: well under a few times the limit.
    EXPECT_LT(out.seconds, 3.0);

    // Without a target, tiles double their samples, least sampled first, until the time is up.
    const RenderOutput timed = TimeLimited({.time_limit = 0.3}, 40);
    EXPECT_TRUE(timed.adaptive.timed_out);
    EXPECT_GE(timed.adaptive.min_spp, 16u);
    EXPECT_LT(timed.seconds, 3.0);
}

}  // namespace
}  // namespace lf
