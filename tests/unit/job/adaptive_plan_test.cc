// The adaptive plan on synthetic tiles whose noise is known: which tiles get more passes, how
// many samples they ask for, what a time limit drops, and that replaying results in index order
// rebuilds the same plan (the farm's recovery).
#include "lf/job/adaptive_plan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "lf/core/image_error.h"

namespace lf {
namespace {

// A 16x8 image in two 8x8 tiles: tile 0 (x < 8) is flat, tile 1 has Gaussian noise of relative
// standard deviation `kSigma` around 0.5. A sample depends on (pixel, sample index) only, as a
// renderer's does.
constexpr double kSigma = 0.5;

TileSums Pass(const RenderTask& task) {
    TileSums sums(task.rect);
    for (int y = task.rect.y0; y < task.rect.y0 + task.rect.height; ++y) {
        for (int x = task.rect.x0; x < task.rect.x0 + task.rect.width; ++x) {
            for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) {
                std::mt19937_64 rng(uint64_t(y * 16 + x) << 32 | s);
                const double noise = x < 8 ? 0 : std::normal_distribution<>(0, kSigma)(rng);
                sums.at(x, y).Add(s, Rgb(float(0.5 * (1 + noise))));
            }
        }
    }
    return sums;
}

std::unique_ptr<AdaptiveTilePlan> MakePlan(const AdaptiveSettings& settings, uint64_t first = 4,
                                           uint64_t max_task_samples = kMaxTaskSamples) {
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> plan =
        AdaptiveTilePlan::Make(16, 8, first, 8, settings, max_task_samples);
    EXPECT_TRUE(plan.ok()) << plan.status();
    return std::move(*plan);
}

// Runs every planned pass to the end, in plan order; returns the results by task index.
std::map<int, TileSums> RunToEnd(AdaptiveTilePlan& plan) {
    std::map<int, TileSums> results;
    for (size_t t = 0; t < plan.tasks().size(); ++t) {
        const RenderTask task = plan.tasks()[t];
        if (!plan.IsPending(int(t))) continue;
        results.emplace(int(t), Pass(task));
        EXPECT_TRUE(plan.Merge(int(t), results.at(int(t))).ok());
    }
    return results;
}

TEST(NextSampleCount, FollowsTheSquareLawWithinItsBounds) {
    // 16 (0.2 / 0.1)^2 1.1 = 70.4 -> 72 (even).
    EXPECT_EQ(NextSampleCount(16, 0.2, 0.1, 1 << 16), 72u);
    EXPECT_EQ(NextSampleCount(16, 0.101, 0.1, 1 << 16), 18u);  // at least 2 more
    EXPECT_EQ(NextSampleCount(16, 10, 0.1, 1 << 16), 128u);    // at most 8x
    EXPECT_EQ(NextSampleCount(16, 0.2, 0.1, 40), 40u);         // at most max_spp
}

TEST(AdaptiveTilePlan, OnlyTheNoisyTileGetsMorePassesUntilItsErrorIsBelowTheTarget) {
    const double target = 0.02;
    auto plan = MakePlan({.target_error = target, .time_limit = 0, .max_spp = 1 << 16});
    ASSERT_EQ(plan->tasks().size(), 2u);
    RunToEnd(*plan);
    ASSERT_TRUE(plan->Complete());
    absl::StatusOr<AdaptiveReport> report = plan->Report();
    ASSERT_TRUE(report.ok()) << report.status();
    EXPECT_EQ(report->per_tile[0].spp, 4u);  // flat: error 0 after the first pass
    EXPECT_EQ(report->per_tile[0].error, 0);
    EXPECT_LE(report->per_tile[1].error, target);
    EXPECT_EQ(report->tiles_above_target, 0);
    // The relative error of a mean of n samples is sigma / sqrt(n) per channel here, so the
    // noisy tile needs about (sigma / target)^2 = 625 samples; the 10 % margin and rounding of
    // the last pass may overshoot, by at most 8x of the pass before.
    const double needed = kSigma * kSigma / (target * target);
    EXPECT_GE(double(report->per_tile[1].spp), 0.8 * needed);
    EXPECT_LE(double(report->per_tile[1].spp), 3 * needed);
    // Every pass after the first belongs to tile 1 and continues where the last one ended.
    uint64_t end = plan->tasks()[1].sample_end;
    for (size_t t = 2; t < plan->tasks().size(); ++t) {
        EXPECT_EQ(plan->tasks()[t].rect.x0, 8);
        EXPECT_EQ(plan->tasks()[t].sample_begin, end);
        end = plan->tasks()[t].sample_end;
    }
}

TEST(AdaptiveTilePlan, WithoutATargetTilesDoubleUpToMaxSpp) {
    auto plan = MakePlan({.target_error = 0, .time_limit = 10, .max_spp = 64});
    RunToEnd(*plan);
    absl::StatusOr<AdaptiveReport> report = plan->Report();
    ASSERT_TRUE(report.ok());
    EXPECT_EQ(report->min_spp, 64u);
    EXPECT_EQ(report->max_spp, 64u);
    EXPECT_EQ(plan->tasks().size(), 2u * 5);  // 4, 8, 16, 32, 64
}

TEST(AdaptiveTilePlan, StopDropsPlannedPassesButNotFirstOnes) {
    auto plan = MakePlan({.target_error = 0.001, .time_limit = 1, .max_spp = 1 << 16});
    // Tile 1's first pass asks for a second; tile 0's first pass is still out.
    absl::StatusOr<std::vector<RenderTask>> next = plan->Merge(1, Pass(plan->tasks()[1]));
    ASSERT_TRUE(next.ok());
    ASSERT_EQ(next->size(), 1u);
    const int second = (*next)[0].index;
    EXPECT_EQ(plan->Stop(), std::vector<int>{second});
    EXPECT_FALSE(plan->IsPending(second));
    EXPECT_EQ(plan->Merge(second, Pass(plan->tasks()[size_t(second)])).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_FALSE(plan->Complete());  // tile 0 has no samples yet
    next = plan->Merge(0, Pass(plan->tasks()[0]));
    ASSERT_TRUE(next.ok());
    EXPECT_TRUE(next->empty());
    EXPECT_TRUE(plan->Complete());
    absl::StatusOr<AdaptiveReport> report = plan->Report();
    ASSERT_TRUE(report.ok());
    EXPECT_TRUE(report->timed_out);
    EXPECT_EQ(report->max_spp, 4u);
    EXPECT_EQ(report->tiles_above_target, 1);
}

TEST(AdaptiveTilePlan, RefusesResultsThatAreNotThePass) {
    auto plan = MakePlan({.target_error = 0.01, .time_limit = 0, .max_spp = 1 << 16});
    RenderTask wrong_count = plan->tasks()[1];
    wrong_count.sample_end = 6;
    EXPECT_EQ(plan->Merge(1, Pass(wrong_count)).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(plan->Merge(1, Pass(plan->tasks()[0])).status().code(),
              absl::StatusCode::kInvalidArgument);  // tile 0's rectangle
    EXPECT_EQ(plan->Merge(7, Pass(plan->tasks()[0])).status().code(),
              absl::StatusCode::kInvalidArgument);
    ASSERT_TRUE(plan->Merge(0, Pass(plan->tasks()[0])).ok());
    EXPECT_EQ(plan->Merge(0, Pass(plan->tasks()[0])).status().code(),
              absl::StatusCode::kAlreadyExists);
    EXPECT_EQ(plan->tasks_done(), 1u);
}

TEST(AdaptiveTilePlan, ReplayingResultsInIndexOrderRebuildsThePlanAndItsBits) {
    const AdaptiveSettings settings{.target_error = 0.02, .time_limit = 0, .max_spp = 1 << 16};
    auto plan = MakePlan(settings);
    const std::map<int, TileSums> results = RunToEnd(*plan);
    auto replayed = MakePlan(settings);
    for (const auto& [t, sums] : results) ASSERT_TRUE(replayed->Merge(t, sums).ok()) << t;
    ASSERT_EQ(replayed->tasks().size(), plan->tasks().size());
    for (size_t t = 0; t < plan->tasks().size(); ++t) {
        EXPECT_EQ(replayed->tasks()[t].sample_end, plan->tasks()[t].sample_end);
    }
    EXPECT_TRUE(replayed->Complete());
    EXPECT_EQ(*replayed->Snapshot()->FindChannel("R"), *plan->Snapshot()->FindChannel("R"));
}

// Long passes are split into tasks of consecutive sample ranges, each of even length, which
// merge in any order into the bits of the unsplit pass; the tile decides once all are in.
TEST(AdaptiveTilePlan, LongPassesSplitIntoTasksThatMergeToTheSameBits) {
    const AdaptiveSettings settings{.target_error = 0.02, .time_limit = 0, .max_spp = 1 << 16};
    auto whole = MakePlan(settings);
    RunToEnd(*whole);
    // 8 samples of a 64-pixel tile per task; the first pass (4 spp) fits one.
    auto split = MakePlan(settings, 4, 8 * 64);
    ASSERT_EQ(split->tasks().size(), 2u);
    std::vector<int> out = {0, 1};
    while (!out.empty()) {
        // The last task appended first: any order must do.
        const int t = out.back();
        out.pop_back();
        absl::StatusOr<std::vector<RenderTask>> next =
            split->Merge(t, Pass(split->tasks()[size_t(t)]));
        ASSERT_TRUE(next.ok()) << next.status();
        // A next pass comes only once no task of the tile's pass is out.
        for (const RenderTask& task : *next) {
            for (int o : out) EXPECT_NE(split->tasks()[size_t(o)].rect.x0, task.rect.x0);
        }
        for (const RenderTask& task : *next) {
            EXPECT_LE(task.sample_end - task.sample_begin, 8u);
            EXPECT_EQ((task.sample_end - task.sample_begin) % 2, 0u);
            out.insert(out.begin(), task.index);
        }
    }
    ASSERT_TRUE(split->Complete());
    EXPECT_GT(split->tasks().size(), whole->tasks().size());
    EXPECT_EQ(*split->Snapshot()->FindChannel("R"), *whole->Snapshot()->FindChannel("R"));
    EXPECT_EQ(*split->Snapshot()->FindChannel("spp"), *whole->Snapshot()->FindChannel("spp"));
}

// A split first pass is never dropped; a split later pass keeps the tasks merged before.
TEST(AdaptiveTilePlan, StopKeepsSplitFirstPassesAndMergedParts) {
    auto plan = MakePlan({.target_error = 0.001, .time_limit = 1, .max_spp = 1 << 16}, 16, 8 * 64);
    ASSERT_EQ(plan->tasks().size(), 4u);  // two tasks of 8 samples per tile
    EXPECT_TRUE(plan->Stop().empty());
    for (int t = 0; t < 4; ++t) ASSERT_TRUE(plan->Merge(t, Pass(plan->tasks()[size_t(t)])).ok());
    EXPECT_TRUE(plan->Complete());

    auto later = MakePlan({.target_error = 0.001, .time_limit = 1, .max_spp = 1 << 16}, 16, 8 * 64);
    for (int t : {2, 3}) ASSERT_TRUE(later->Merge(t, Pass(later->tasks()[size_t(t)])).ok());
    ASSERT_GT(later->tasks().size(), 5u);  // tile 1's second pass, split
    ASSERT_TRUE(later->Merge(4, Pass(later->tasks()[4])).ok());
    const std::vector<int> dropped = later->Stop();
    EXPECT_EQ(dropped.size(), later->tasks().size() - 5);
    for (int t : {0, 1}) ASSERT_TRUE(later->Merge(t, Pass(later->tasks()[size_t(t)])).ok());
    EXPECT_TRUE(later->Complete());
    absl::StatusOr<AdaptiveReport> report = later->Report();
    ASSERT_TRUE(report.ok());
    EXPECT_EQ(report->per_tile[1].spp, later->tasks()[4].sample_end);
}

// A farm preview reports on a plan with tiles not sampled yet.
TEST(AdaptiveTilePlan, ReportsBeforeEveryTileHasSamples) {
    auto plan = MakePlan({.target_error = 0.02, .time_limit = 0, .max_spp = 1 << 16});
    ASSERT_TRUE(plan->Merge(1, Pass(plan->tasks()[1])).ok());
    absl::StatusOr<AdaptiveReport> report = plan->Report();
    ASSERT_TRUE(report.ok()) << report.status();
    EXPECT_EQ(report->min_spp, 0u);
    EXPECT_EQ(report->per_tile[1].spp, 4u);
    EXPECT_TRUE(std::isfinite(report->estimated_error));
}

TEST(AdaptiveTilePlan, RefusesSettingsOutOfRange) {
    for (const AdaptiveSettings& bad :
         {AdaptiveSettings{.target_error = -0.1}, AdaptiveSettings{.target_error = NAN},
          AdaptiveSettings{.time_limit = -1}, AdaptiveSettings{.time_limit = INFINITY},
          AdaptiveSettings{.target_error = 0.1, .max_spp = 1},
          AdaptiveSettings{.target_error = 0.1, .max_spp = kMaxSpp + 1}}) {
        EXPECT_EQ(AdaptiveTilePlan::Make(16, 8, 4, 8, bad).status().code(),
                  absl::StatusCode::kInvalidArgument);
    }
}

}  // namespace
}  // namespace lf
