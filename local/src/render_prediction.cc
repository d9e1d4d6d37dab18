#include "lf/local/render_prediction.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace lf {

namespace {

uint64_t RoundUpToEven(uint64_t n) { return n + (n & 1); }

double ErrorAt(const TilePilot& tile, double rate, uint64_t n) {
    const double x = double(n);
    // A first stage without noise (every sample black: the light the tile sees is rare)
    // measured nothing to interpolate from: up to n2 the error is the second stage's at the
    // Monte Carlo rate, not 0 (or 0 times infinity between the stages, which stopped the replay).
    if (!(tile.e1 > 0) && x <= double(tile.n2)) return tile.e2 * std::sqrt(double(tile.n2) / x);
    if (x <= double(tile.n1)) return tile.e1 * std::sqrt(double(tile.n1) / x);
    if (x <= double(tile.n2)) {
        const double t = std::log(x / double(tile.n1)) / std::log(double(tile.n2) / tile.n1);
        return tile.e1 * std::pow(tile.e2 / tile.e1, t);
    }
    return tile.e2 * std::pow(x / double(tile.n2), -rate);
}

// The tiles' errors after a render of `spp` samples per pixel in every tile.
absl::StatusOr<RenderOutput> PilotStage(const Camera& camera, const RadianceEstimator& estimator,
                                        RenderSettings settings, double target, uint64_t spp) {
    settings.spp = spp;
    return RenderImageAdaptive(camera, estimator, settings,
                               AdaptiveSettings{.target_error = target, .max_spp = spp});
}

}  // namespace

double ConvergenceRate(const TilePilot& tile) {
    if (!(tile.e1 > 0) || !(tile.e2 > 0)) return 0.5;  // a black tile: nothing to measure
    const double rate = std::log(tile.e1 / tile.e2) / std::log(double(tile.n2) / tile.n1);
    return std::clamp(rate, kMinConvergenceRate, kMaxConvergenceRate);
}

uint64_t PredictTileSamples(const TilePilot& tile, double rate, uint64_t first, double target,
                            uint64_t max_spp) {
    max_spp = RoundUpToEven(max_spp);
    uint64_t n = std::min(max_spp, RoundUpToEven(std::max<uint64_t>(first, 2)));
    double error = ErrorAt(tile, rate, n);
    while (error > target && n < max_spp) {
        n = NextSampleCount(n, error, target, max_spp);
        error = ErrorAt(tile, rate, n);
    }
    return n;
}

absl::StatusOr<RenderPrediction> PredictAdaptiveRender(const Camera& camera,
                                                       const RadianceEstimator& estimator,
                                                       const RenderSettings& settings,
                                                       const AdaptiveSettings& adaptive,
                                                       uint64_t pilot_spp) {
    if (!(adaptive.target_error > 0)) {
        return absl::InvalidArgumentError(
            absl::StrCat("a prediction needs a target error above 0, not ", adaptive.target_error));
    }
    RenderPrediction p;
    p.pilot_spp[0] = RoundUpToEven(std::max<uint64_t>(pilot_spp, 2));
    p.pilot_spp[1] = 4 * p.pilot_spp[0];
    absl::StatusOr<RenderOutput> first =
        PilotStage(camera, estimator, settings, adaptive.target_error, p.pilot_spp[0]);
    if (!first.ok()) return first.status();
    absl::StatusOr<RenderOutput> second =
        PilotStage(camera, estimator, settings, adaptive.target_error, p.pilot_spp[1]);
    if (!second.ok()) return second.status();
    p.pilot_seconds = first->seconds + second->seconds;
    const double seconds_per_sample =
        second->seconds / std::max(1.0, double(second->stats.samples));

    const std::vector<AdaptiveReport::Tile>& a = first->adaptive.per_tile;
    const std::vector<AdaptiveReport::Tile>& b = second->adaptive.per_tile;
    std::vector<double> rates;
    double samples = 0, high = 0, first_stage = 0, pixels = 0;
    for (size_t t = 0; t < a.size() && t < b.size(); ++t) {
        const TilePilot tile{a[t].rect.Area(), a[t].spp, b[t].spp, a[t].error, b[t].error};
        const double rate = ConvergenceRate(tile);
        if (tile.e1 > 0 && tile.e2 > 0) {
            rates.push_back(std::log(tile.e1 / tile.e2) / std::log(double(tile.n2) / tile.n1));
        }
        if (tile.e2 > 1.5 * tile.e1 * std::sqrt(double(tile.n1) / double(tile.n2))) {
            ++p.tiles_disagreeing;
        }
        const auto predict = [&](const TilePilot& pilot, double r) {
            return double(PredictTileSamples(pilot, r, settings.spp, adaptive.target_error,
                                             adaptive.max_spp));
        };
        const double n = predict(tile, rate);
        const double area = double(tile.pixels);
        samples += n * area;
        high += predict(tile, 0.5) * area;
        // The first stage alone, as if its error fell at the Monte Carlo rate.
        const double e2 = tile.e1 * std::sqrt(double(tile.n1) / double(tile.n2));
        first_stage += predict({tile.pixels, tile.n1, tile.n2, tile.e1, e2}, 0.5) * area;
        pixels += area;
        p.hardest_tile_spp = std::max(p.hardest_tile_spp, uint64_t(n));
        if (uint64_t(n) >= RoundUpToEven(adaptive.max_spp)) ++p.tiles_at_max_spp;
        ++p.tiles;
    }
    if (pixels == 0) return absl::InvalidArgumentError("the pilot rendered no tiles");
    if (!rates.empty()) {
        std::nth_element(rates.begin(), rates.begin() + rates.size() / 2, rates.end());
        p.median_rate = rates[rates.size() / 2];
    }
    p.mean_spp = samples / pixels;
    p.high_mean_spp = high / pixels;
    p.first_stage_mean_spp = first_stage / pixels;
    p.seconds = samples * seconds_per_sample;
    p.high_seconds = high * seconds_per_sample;
    return p;
}

absl::StatusOr<MethodCost> PredictMethodCost(const MethodPilotStage& first,
                                             const MethodPilotStage& second, double target_error,
                                             double min_rate, double max_rate) {
    if (first.spp == 0 || second.spp <= first.spp || !(second.seconds >= 0) ||
        !(target_error > 0) || !(min_rate > 0) || min_rate > max_rate) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "method pilot: stages of %d and %d spp, target error %g, rates [%g, %g]: expected "
            "0 < first < second spp, a positive target and 0 < min rate <= max rate",
            first.spp, second.spp, target_error, min_rate, max_rate));
    }
    MethodCost cost;
    cost.stages[0] = first;
    cost.stages[1] = second;
    const double log_spp = std::log(double(second.spp) / double(first.spp));
    const double measured = first.error > 0 && second.error > 0
                                ? std::log(first.error / second.error) / log_spp
                                : min_rate;
    cost.rate = std::clamp(measured, min_rate, max_rate);
    if (!(second.error > 0)) {  // nothing left to converge (a black or noiseless image)
        cost.spp = double(first.spp);
        cost.seconds = first.seconds;
        return cost;
    }
    const double factor = std::pow(second.error / target_error, 1 / cost.rate);
    cost.spp = double(second.spp) * std::max(1.0, factor);
    cost.seconds = second.seconds * cost.spp / double(second.spp);
    return cost;
}

}  // namespace lf
