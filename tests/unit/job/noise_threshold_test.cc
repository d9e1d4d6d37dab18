// Per-pixel adaptive sampling (--noise-threshold): Cycles' error and stopping rule on pixels
// worked by hand, the check points, the masks a plan gives its passes, what a worker refuses,
// and that a pixel's samples do not depend on the tile it is in.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "lf/job/adaptive_plan.h"
#include "lf/job/merge.h"

namespace lf {
namespace {

// Even samples `even`, odd samples `odd`, `pairs` of each.
PixelSums Halves(const Rgb& even, const Rgb& odd, int pairs = 4) {
    PixelSums p;
    for (int s = 0; s < 2 * pairs; ++s) p.Add(uint64_t(s), s % 2 == 0 ? even : odd);
    return p;
}

TEST(PixelNoiseError, IsCyclesErrorOfTheHalves) {
    // I = 2, A = 1 in every channel: (1 + 1 + 1) / (1e-4 + sqrt(6)).
    EXPECT_NEAR(PixelNoiseError(Halves(Rgb(1), Rgb(3))), 3 / (1e-4 + std::sqrt(6.0)), 1e-7);
    // I = (0.6, 0.2, 0.2), |I - A| = (0.1, 0, 0.1): 0.2 / (1e-4 + sqrt(1)).
    const PixelSums p = Halves({0.5f, 0.2f, 0.1f}, {0.7f, 0.2f, 0.3f});
    EXPECT_NEAR(PixelNoiseError(p), 0.2 / 1.0001, 1e-7);
    EXPECT_EQ(PixelNoiseError(Halves(Rgb(0), Rgb(0))), 0);  // black: 0, not 0 / 0
    // Converged strictly below 5 T, as Cycles: 0.19998 < 0.2 but not < 0.195.
    EXPECT_TRUE(PixelConverged(p, 0.04));
    EXPECT_FALSE(PixelConverged(p, 0.039));
}

TEST(NoiseThreshold, MinSppAndCheckPointsAreCycles) {
    // Cycles' comment: threshold 0.1 -> 32, 0.01 -> 64, 0.001 -> 128.
    EXPECT_EQ(NoiseThresholdMinSpp(0.1), 32u);
    EXPECT_EQ(NoiseThresholdMinSpp(0.01), 64u);
    EXPECT_EQ(NoiseThresholdMinSpp(0.001), 128u);
    EXPECT_EQ(NoiseThresholdMinSpp(1), 16u);
    EXPECT_EQ(NextNoiseCheck(4, 1 << 16), 20u);   // Cycles' step of 16
    EXPECT_EQ(NextNoiseCheck(64, 1 << 16), 80u);  // a quarter more from 64 on
    EXPECT_EQ(NextNoiseCheck(200, 1 << 16), 250u);
    EXPECT_EQ(NextNoiseCheck(200, 210), 210u);  // at most max_spp
}

// A 16x8 image: pixels with x < 8 are flat; the others have Gaussian noise whose relative
// standard deviation grows with x, so they need more samples the further right they are.
TileSums Pass(const RenderTask& task) {
    TileSums sums(task.rect);
    const PixelMask active = task.active();
    for (int y = task.rect.y0; y < task.rect.y0 + task.rect.height; ++y) {
        for (int x = task.rect.x0; x < task.rect.x0 + task.rect.width; ++x) {
            if (!active.Has(x, y)) continue;
            for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) {
                std::mt19937_64 rng(uint64_t(y * 16 + x) << 32 | s);
                const double sigma = x < 8 ? 0 : 0.1 * (x - 7);
                const double noise = std::normal_distribution<>(0, sigma)(rng);
                sums.at(x, y).Add(s, Rgb(float(0.5 * (1 + noise))));
            }
        }
    }
    return sums;
}

struct PlanRun {
    Image image;
    AdaptiveReport report;
    std::vector<RenderTask> tasks;
};

PlanRun RunToEnd(int tile, const AdaptiveSettings& settings, uint64_t max_task_samples = 1 << 20) {
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> made =
        AdaptiveTilePlan::Make(16, 8, 16, tile, settings, max_task_samples);
    EXPECT_TRUE(made.ok()) << made.status();
    AdaptiveTilePlan& plan = **made;
    for (size_t t = 0; t < plan.tasks().size(); ++t) {
        const RenderTask task = plan.tasks()[t];
        EXPECT_TRUE(plan.Merge(int(t), Pass(task)).ok());
    }
    EXPECT_TRUE(plan.Complete());
    absl::StatusOr<Image> image = plan.Snapshot();
    EXPECT_TRUE(image.ok()) << image.status();
    return {*std::move(image), plan.TileReport(), plan.tasks()};
}

const AdaptiveSettings kSettings{.max_spp = 4096, .noise_threshold = 0.01};

TEST(NoiseThresholdPlan, SamplesOnlyUnconvergedPixelsAndEachStopsByItsOwnSamples) {
    const PlanRun run = RunToEnd(8, kSettings);
    const std::vector<float>& spp = *run.image.FindChannel("spp");
    const std::vector<float>& r = *run.image.FindChannel("R");
    const std::vector<float>& a = *run.image.FindChannel("A.R");
    const std::vector<float>& b = *run.image.FindChannel("B.R");
    double flat = 0, noisiest = 0;
    for (int y = 0; y < 8; ++y) {
        flat += spp[size_t(y) * 16 + 0] / 8;
        noisiest += spp[size_t(y) * 16 + 15] / 8;
        for (int x = 0; x < 16; ++x) {
            const size_t i = size_t(y) * 16 + x;
            // Every pixel stopped converged by the rule on its halves (grey: 3 equal channels)
            // or at max_spp.
            const uint64_t n = uint64_t(spp[i]);
            EXPECT_NEAR(r[i], (a[i] + b[i]) / 2, 1e-6);
            const double error = 3 * std::abs(r[i] - a[i]) / (1e-4 + std::sqrt(3 * r[i]));
            EXPECT_TRUE(error < 5 * kSettings.noise_threshold * (1 + 1e-4) || n == 4096)
                << x << "," << y << ": " << n << " spp, error " << error;
        }
    }
    EXPECT_EQ(flat, 16);  // error 0 after the minimum
    // Relative sigma 0.9 around 0.5: Cycles' error has mean 3 x 0.8 x 0.45 / sqrt(n) /
    // sqrt(1.5) (E|N(0, s)| = 0.8 s), which reaches 0.05 at n = 310; one check on a noisy
    // error stops some pixels far earlier, so only the order is sure.
    EXPECT_GT(noisiest, 4 * flat);
    EXPECT_EQ(run.report.min_spp, 16u);
    EXPECT_EQ(run.report.pixels, 128);
    EXPECT_EQ(run.report.pixels_unconverged, 0);
    // Passes after the first sample only the pixels still active: the flat tile gets none.
    for (const RenderTask& task : run.tasks) {
        if (task.sample_begin > 0) {
            EXPECT_EQ(task.rect.x0, 8);
            EXPECT_LE(task.ActivePixels(), 64);
        }
    }
}

TEST(NoiseThresholdPlan, PixelsAreTheSameBitsForAnyTileSizeAndTaskSplit) {
    const PlanRun eight = RunToEnd(8, kSettings), four = RunToEnd(4, kSettings),
                  split = RunToEnd(16, kSettings, 100);
    for (const char* c : {"R", "G", "A.B", "B.R", "spp"}) {
        EXPECT_EQ(*eight.image.FindChannel(c), *four.image.FindChannel(c)) << c;
        EXPECT_EQ(*eight.image.FindChannel(c), *split.image.FindChannel(c)) << c;
    }
    EXPECT_GT(split.tasks.size(), eight.tasks.size());
}

TEST(NoiseThresholdPlan, EveryTaskOfAnOddMaxSppPassesTheWorkersCheck) {
    const AdaptiveSettings odd{.max_spp = 101, .noise_threshold = 0.001};
    const PlanRun run = RunToEnd(8, odd);
    EXPECT_EQ(run.report.max_spp, 102u);
    for (const RenderTask& task : run.tasks) {
        EXPECT_TRUE(CheckActivePixels(task, odd).ok()) << CheckActivePixels(task, odd);
    }
}

TEST(NoiseThresholdPlan, TakesAtLeastFourSamplesAPixel) {
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> made =
        AdaptiveTilePlan::Make(16, 8, 2, 8, kSettings, 1 << 20);
    ASSERT_TRUE(made.ok()) << made.status();
    EXPECT_EQ((*made)->tasks()[0].sample_end, kMinNoiseThresholdSpp);
}

TEST(NoiseThresholdPlan, StopsAtMaxSppAndCountsWhatDidNotConverge) {
    const PlanRun run = RunToEnd(8, {.max_spp = 64, .noise_threshold = 0.001});
    EXPECT_EQ(run.report.max_spp, 64u);
    EXPECT_GT(run.report.pixels_unconverged, 0);
    EXPECT_LE(run.report.pixels_unconverged, 64);  // the flat pixels converge
}

// One 16x8 tile whose first pass has merged, so that its second pass samples the noisy half.
std::unique_ptr<AdaptiveTilePlan> AfterTheFirstPass() {
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> made =
        AdaptiveTilePlan::Make(16, 8, 16, 16, kSettings);
    EXPECT_TRUE(made.ok()) << made.status();
    EXPECT_TRUE((*made)->Merge(0, Pass((*made)->tasks()[0])).ok());
    EXPECT_EQ((*made)->tasks().size(), 2u);
    return *std::move(made);
}

TEST(NoiseThresholdPlan, RefusesAResultWithSamplesInAConvergedPixel) {
    const std::unique_ptr<AdaptiveTilePlan> made = AfterTheFirstPass();
    ASSERT_EQ(made->tasks().size(), 2u);
    AdaptiveTilePlan& plan = *made;
    RenderTask all = plan.tasks()[1];
    ASSERT_FALSE(all.active_pixels.empty());
    all.active_pixels.clear();  // a worker that sampled every pixel
    const absl::StatusOr<std::vector<RenderTask>> merged = plan.Merge(1, Pass(all));
    EXPECT_EQ(merged.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(merged.status().message().find("has 16 samples, the task 0"), std::string::npos)
        << merged.status();
}

TEST(NoiseThresholdPlan, RefusesSumsOutsideTheMaskAndUnbalancedHalves) {
    const std::unique_ptr<AdaptiveTilePlan> made = AfterTheFirstPass();
    ASSERT_EQ(made->tasks().size(), 2u);
    AdaptiveTilePlan& plan = *made;
    const RenderTask next = plan.tasks()[1];
    const PixelMask mask = next.active();
    size_t outside = 0, inside = 0;
    while (mask.Has(outside)) ++outside;
    while (!mask.Has(inside)) ++inside;

    TileSums touched = Pass(next);
    touched.pixels[outside].sum[0][0].Add(1.0f);  // no samples, yet sums
    absl::StatusOr<std::vector<RenderTask>> merged = plan.Merge(1, touched);
    EXPECT_EQ(merged.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(merged.status().message().find("is not sampled by the task but has sums"),
              std::string::npos)
        << merged.status();

    TileSums unbalanced = Pass(next);
    PixelSums& p = unbalanced.pixels[inside];
    ++p.count[0];  // as many samples, one more of them even
    --p.count[1];
    merged = plan.Merge(1, unbalanced);
    EXPECT_EQ(merged.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(merged.status().message().find("even samples, the task"), std::string::npos)
        << merged.status();
    EXPECT_TRUE(plan.Merge(1, Pass(next)).ok());  // nothing of the refused results stuck
}

TEST(CheckActivePixels, RefusesMalformedMasks) {
    RenderTask task{7, {0, 0, 5, 2}, 16, 32, std::string("\x01\x02", 2)};
    EXPECT_TRUE(CheckActivePixels(task, kSettings).ok());
    const auto refused = [&](const RenderTask& t, const AdaptiveSettings& s,
                             const std::string& words) {
        const absl::Status status = CheckActivePixels(t, s);
        EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << words;
        EXPECT_NE(status.message().find(words), std::string::npos) << status;
        EXPECT_NE(status.message().find("task 7"), std::string::npos) << status;
    };
    RenderTask t = task;
    t.active_pixels = "\x01";
    refused(t, kSettings, "1 bytes, expected 2 (one bit per pixel of 5x2)");
    t.active_pixels = std::string("\x01\x04", 2);  // bit 10 of 10 pixels
    refused(t, kSettings, "a bit past the last pixel");
    t.active_pixels = std::string("\x00\x00", 2);
    refused(t, kSettings, "none set");
    refused(task, {.max_spp = 24, .noise_threshold = 0.01}, "beyond the job's max_spp 24");
    // An odd max_spp: the plan's last pass ends at the even count above it.
    EXPECT_TRUE(CheckActivePixels(task, {.max_spp = 31, .noise_threshold = 0.01}).ok());
    refused(task, {.max_spp = 29, .noise_threshold = 0.01}, "beyond the job's max_spp 29");
    refused(task, {.target_error = 0.1}, "without a noise threshold");
    task.active_pixels.clear();  // every pixel: any job
    EXPECT_TRUE(CheckActivePixels(task, {.target_error = 0.1}).ok());
}

TEST(CheckAdaptiveSettings, RefusesNoiseThresholdsOutOfRangeOrWithATarget) {
    EXPECT_TRUE(CheckAdaptiveSettings({.noise_threshold = 1}).ok());
    for (const double t : {-0.1, 1.5, std::nan("")}) {
        const absl::Status s = CheckAdaptiveSettings({.noise_threshold = t});
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << t;
        EXPECT_NE(s.message().find("noise threshold"), std::string::npos) << s;
    }
    const absl::Status both = CheckAdaptiveSettings({.target_error = 0.1, .noise_threshold = 0.1});
    EXPECT_NE(both.message().find("pick one"), std::string::npos) << both;
}

}  // namespace
}  // namespace lf
