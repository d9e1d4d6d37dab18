// What `render --target-error E` will cost, predicted before it runs (`lightfarm plan`): a pilot
// in two stages measures each tile's error and how fast it falls, and the adaptive plan's pass
// rule (NextSampleCount) is replayed on that model, tile by tile.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/camera.h"
#include "lf/job/adaptive_plan.h"
#include "lf/kernels/radiance.h"
#include "lf/local/local_executor.h"

namespace lf {

// A tile's estimated error (EstimatedTileError) after each pilot stage.
struct TilePilot {
    int64_t pixels = 0;
    uint64_t n1 = 0, n2 = 0;  // n1 < n2
    double e1 = 0, e2 = 0;
};

// The measured rate is clamped to this. A rate below 1/2 between the stages is the estimate
// catching up with noise the first stage did not see (caustics, fireflies); once seen, the
// error of a mean of finite variance falls as n^-1/2. Extrapolating a lower rate predicted
// 18x the samples on the glTF demo (one tile at max_spp) and 2.5x on materials.json
// (docs/convergence.md). Sobol on a smooth tile reaches about 3/4, nothing here faster than 1.
inline constexpr double kMinConvergenceRate = 0.5, kMaxConvergenceRate = 1.0;

// The exponent of e(n) = e2 (n / n2)^-rate through the tile's two points, clamped.
double ConvergenceRate(const TilePilot& tile);

// The samples the tile ends with when its passes follow AdaptiveTilePlan: a first pass of
// `first` samples, then NextSampleCount after each pass, until the error is at most `target` or
// the tile has `max_spp`. The error after n samples is log-linear in n between the pilot's two
// points, the power law of exponent `rate` through (n2, e2) above them, and falls as n^-1/2
// below n1 (below n2 through (n2, e2) when e1 is 0: a first stage that saw no noise).
uint64_t PredictTileSamples(const TilePilot& tile, double rate, uint64_t first, double target,
                            uint64_t max_spp);

struct RenderPrediction {
    double mean_spp = 0;       // over the pixels, from the tiles' measured rates
    double high_mean_spp = 0;  // the same with every rate 1/2: Sobol's faster rate may not last
    uint64_t hardest_tile_spp = 0;         // the most any tile takes
    int tiles = 0, tiles_at_max_spp = 0;   // predicted to stop at max_spp, not the target
    double seconds = 0, high_seconds = 0;  // at the pilot's speed
    double median_rate = 0;                // of the tiles' measured rates (before clamping)
    // The tiles whose second stage's error is more than 1.5x what the first stage predicted at
    // the Monte Carlo rate 1/2: noise the first stage did not see (fireflies, caustics).
    int tiles_disagreeing = 0;
    uint64_t pilot_spp[2] = {0, 0};
    double pilot_seconds = 0;
    double first_stage_mean_spp = 0;  // what the first stage alone predicts at rate 1/2
};

// Runs the pilot, stage 1 of `pilot_spp` and stage 2 of 4x that many samples per pixel (even),
// every tile at the full resolution with the render's tiles, seed, sampler and clamp
// (`settings`; settings.spp is the render's first pass), and predicts the render for
// `adaptive` (its target_error must be above 0). The render's errors for the tiles' first
// passes are those of the pilot when pilot_spp equals settings.spp. InvalidArgument for
// settings the renderer refuses.
absl::StatusOr<RenderPrediction> PredictAdaptiveRender(const Camera& camera,
                                                       const RadianceEstimator& estimator,
                                                       const RenderSettings& settings,
                                                       const AdaptiveSettings& adaptive,
                                                       uint64_t pilot_spp);

// `plan`'s comparison of methods: each method's whole-image error, the square root of its A/B
// relMSE estimate (EstimatedRelMse), after a pilot of two stages, extrapolated along the power
// law through them to the spp and seconds a target error takes at the method's own speed.
struct MethodPilotStage {
    uint64_t spp = 0;
    double seconds = 0;
    double error = 0;
};

struct MethodCost {
    MethodPilotStage stages[2];
    double rate = 0;     // of error ~ spp^-rate, measured between the stages and clamped
    double spp = 0;      // to reach the target error (at least the second stage's)
    double seconds = 0;  // at the second stage's samples per second
};

// From the two stages (stages[0].spp < stages[1].spp) and the clamp of the rate: unbiased
// Monte Carlo [kMinConvergenceRate, kMaxConvergenceRate]; photon mapping's noise falls as
// N^(-alpha/2), its own clamp. InvalidArgument when a stage is empty or the target is not
// positive; a method whose error is 0 costs its first stage.
absl::StatusOr<MethodCost> PredictMethodCost(const MethodPilotStage& first,
                                             const MethodPilotStage& second, double target_error,
                                             double min_rate, double max_rate);

}  // namespace lf
