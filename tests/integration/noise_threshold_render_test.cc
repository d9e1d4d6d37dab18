// Per-pixel adaptive sampling (--noise-threshold) in real renders: the same bits for any thread
// count and tile size, more samples where a uniform render is noisier, and at equal samples a
// lower relMSE than uniform sampling on a scene whose noise is uneven.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/job/adaptive_plan.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace lf {
namespace {

class NoiseThreshold : public ::testing::Test {
  protected:
    void Load(const std::string& name, int resolution) {
        absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/" + name);
        ASSERT_TRUE(scene.ok()) << scene.status();
        scene_ = *std::move(scene);
        scene_.camera.width = scene_.camera.height = resolution;
        absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(scene_);
        ASSERT_TRUE(embree.ok()) << embree.status();
        embree_ = std::move(*embree);
        camera_ = std::make_unique<Camera>(scene_.camera, embree_->origin());
        tracer_ = std::make_unique<PathTracer>(*embree_, -1);
    }

    RenderOutput Render(uint64_t spp, uint64_t seed, const AdaptiveSettings& adaptive = {},
                        int threads = 2, int tile = 16) {
        RenderSettings settings;
        settings.spp = spp;
        settings.seed = seed;
        settings.threads = threads;
        settings.tile = tile;
        settings.sampler = SamplerType::kSobol;
        absl::StatusOr<RenderOutput> out =
            IsAdaptive(adaptive) ? RenderImageAdaptive(*camera_, *tracer_, settings, adaptive)
                                 : RenderImage(*camera_, *tracer_, settings);
        EXPECT_TRUE(out.ok()) << out.status();
        return *std::move(out);
    }

    Scene scene_;  // the Embree scene refers to it
    std::unique_ptr<EmbreeScene> embree_;
    std::unique_ptr<Camera> camera_;
    std::unique_ptr<PathTracer> tracer_;
};

const std::vector<float>& Channel(const RenderOutput& out, const char* name) {
    return *out.image.FindChannel(name);
}

// Cycles' error of each pixel of an image (PixelNoiseError of its halves).
std::vector<double> CyclesErrors(const RenderOutput& out) {
    std::vector<double> e(Channel(out, "R").size());
    for (size_t i = 0; i < e.size(); ++i) {
        double difference = 0, sum = 0;
        for (const char* c : {"R", "G", "B"}) {
            const std::string ch(c);
            difference += std::abs(Channel(out, c)[i] - Channel(out, ("A." + ch).c_str())[i]);
            sum += Channel(out, c)[i];
        }
        e[i] = difference / (1e-4 + std::sqrt(std::max(sum, 0.0)));
    }
    return e;
}

TEST_F(NoiseThreshold, SameBitsForAnyThreadCountAndTileSize) {
    Load("cornell_box.json", 32);
    const AdaptiveSettings adaptive{.max_spp = 256, .noise_threshold = 0.05};
    const RenderOutput base = Render(8, 3, adaptive, 1, 8);
    const RenderOutput threads = Render(8, 3, adaptive, 2, 8);
    const RenderOutput tile = Render(8, 3, adaptive, 2, 32);
    for (const char* c : {"R", "G", "B", "A.R", "B.G", "spp"}) {
        EXPECT_EQ(Channel(base, c), Channel(threads, c)) << c;
        EXPECT_EQ(Channel(base, c), Channel(tile, c)) << c;
    }
    EXPECT_GT(base.adaptive.max_spp, base.adaptive.min_spp);
}

// Where an independent uniform render is noisiest by Cycles' measure, the adaptive render took
// more samples than where it is quietest: the quartiles' mean spp, not a hard-coded region.
TEST_F(NoiseThreshold, NoisierPixelsGetMoreSamples) {
    Load("cornell_box.json", 32);
    const RenderOutput uniform = Render(64, 21);
    const RenderOutput adaptive = Render(8, 22, {.max_spp = 1024, .noise_threshold = 0.02});
    const std::vector<double> error = CyclesErrors(uniform);
    std::vector<size_t> order(error.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return error[a] < error[b]; });
    const std::vector<float>& spp = Channel(adaptive, "spp");
    const size_t quarter = order.size() / 4;
    double quiet = 0, noisy = 0;
    for (size_t k = 0; k < quarter; ++k) {
        quiet += spp[order[k]] / double(quarter);
        noisy += spp[order[order.size() - 1 - k]] / double(quarter);
    }
    std::printf("mean spp: quietest quarter %.1f, noisiest %.1f\n", quiet, noisy);
    EXPECT_GT(noisy, 1.5 * quiet);
}

// Per pixel, the relMSE term of `x` against the reference `r`: sum over channels of
// ((x - r)^2 - h^2) / (r^2 + 0.01) / 3, with h^2 = ((A_r - B_r) / 2)^2 the reference's own
// variance, unbiased, so that the reference's noise adds nothing on average.
std::vector<double> RelMse(const RenderOutput& x, const RenderOutput& r) {
    std::vector<double> e(Channel(x, "R").size(), 0);
    for (const char* c : {"R", "G", "B"}) {
        const std::string ch(c);
        const std::vector<float>&xs = Channel(x, c), &rs = Channel(r, c);
        const std::vector<float>&a = Channel(r, ("A." + ch).c_str()),
              &b = Channel(r, ("B." + ch).c_str());
        for (size_t i = 0; i < e.size(); ++i) {
            const double d = double(xs[i]) - rs[i], h = (double(a[i]) - b[i]) / 2;
            e[i] += (d * d - h * h) / (double(rs[i]) * rs[i] + 0.01) / 3;
        }
    }
    return e;
}

// At equal samples (the uniform render takes at least the adaptive one's total), the adaptive
// render's relMSE against an independent reference is lower. Tolerance: the per-pixel
// differences of the two renders' terms are independent across pixels, so their mean is
// normal with the standard error s / sqrt(n); "lower" is a mean difference below -3 standard
// errors (a false pass has probability 0.13 % if they were equal).
TEST_F(NoiseThreshold, LowerRelMseThanUniformAtEqualSamples) {
    Load("materials.json", 48);
    const RenderOutput adaptive = Render(16, 31, {.max_spp = 4096, .noise_threshold = 0.02});
    const std::vector<float>& spp = Channel(adaptive, "spp");
    const double total = std::accumulate(spp.begin(), spp.end(), 0.0);
    const uint64_t even = 2 * uint64_t(std::ceil(total / double(spp.size()) / 2));
    const RenderOutput uniform = Render(even, 32);
    const RenderOutput reference = Render(1024, 33);
    const std::vector<double> a = RelMse(adaptive, reference), u = RelMse(uniform, reference);
    const double n = double(a.size());
    double mean_a = 0, mean_u = 0, sum = 0, sum2 = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        mean_a += a[i] / n;
        mean_u += u[i] / n;
        sum += a[i] - u[i];
        sum2 += (a[i] - u[i]) * (a[i] - u[i]);
    }
    const double mean = sum / n;
    const double error = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
    std::printf(
        "equal samples (%.0f adaptive, %llu uniform per pixel; adaptive %llu..%llu): relMSE "
        "adaptive %.5f, uniform %.5f (ratio %.2f), difference %.5f +- %.5f\n",
        total / n, (unsigned long long)even, (unsigned long long)adaptive.adaptive.min_spp,
        (unsigned long long)adaptive.adaptive.max_spp, mean_a, mean_u, mean_a / mean_u, mean,
        error);
    EXPECT_LT(mean, -3 * error);
}

}  // namespace
}  // namespace lf
