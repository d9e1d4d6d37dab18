// `lightfarm converge`: the trade between time and accuracy, measured. Renders a ladder of
// budgets per method (samples per pixel for the path tracer, patch counts for radiosity) and,
// for the path tracer, per configuration (sampler and light strategy), compares each image with
// one reference and writes convergence.csv, a log-log plot of relative RMSE against time, and
// per configuration the fitted slopes and the error at equal time relative to the first
// configuration (docs/convergence.md).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/error_curve.h"
#include "lf/core/film.h"
#include "lf/core/image_error.h"
#include "lf/core/light_strategy.h"
#include "lf/core/sampler.h"
#include "lf/core/scene_loader.h"
#include "lf/job/method_registry.h"
#include "lf/job/settings.h"
#include "lf/job/splat_settings.h"

namespace lf {

// What a ladder varies: the method (the path tracer or a splatting method: light, bdpt, ppm), where
// the random numbers come from and how next-event estimation picks lights.
struct RenderConfig {
    Method method = Method::kPath;
    SamplerType sampler = defaults::kSampler;
    LightStrategy light_strategy = defaults::kLightStrategy;
    bool operator==(const RenderConfig&) const = default;
};

// The methods converge renders as spp ladders: budget = spp (light paths per pixel for light,
// photon passes for ppm).
bool IsLadderMethod(Method method);

// "sobol/bvh" for the path tracer, "bdpt/sobol/bvh" for the others: how the table, the plot and
// --compare name it.
std::string ConfigName(const RenderConfig& config);

// --compare "independent/power,sobol/bvh,bdpt/sobol/bvh": configurations in the order given,
// each [METHOD/]SAMPLER/LIGHTS (METHOD a ladder method, path when left out).
absl::StatusOr<std::vector<RenderConfig>> ParseConfigList(const std::string& list);

// --sampler and --light-sampling lists ("independent,sobol" and "power,bvh"): every pair,
// samplers outermost, so the first configuration pairs the first of each.
absl::StatusOr<std::vector<RenderConfig>> ConfigProduct(const std::string& samplers,
                                                        const std::string& light_strategies);

// --fit-spp "16:1024": the rungs whose slopes the summary fits.
struct SppRange {
    uint64_t from = 16, to = 1024;  // the range
};
absl::StatusOr<SppRange> ParseSppRange(const std::string& text);

struct ConvergenceOptions {
    std::string scene_path;
    std::string out_dir;
    std::string reference_path;  // empty: render our own path-traced reference
    // path | radiosity | both (path and radiosity) | whitted (its ladder against the path-traced
    // reference: the error levels off at what Whitted leaves out) | a comma-separated list of
    // ladder methods (path, light, bdpt, ppm), each laddered in every configuration of `configs`
    std::string method = "both";
    PhotonSettings ppm;      // the ppm ladders' --photons, --ppm-radius, --ppm-alpha
    SceneOptions scene;      // --camera, --resolution
    uint64_t max_spp = 256;  // path ladder 1, 2, 4, ... up to this
    uint64_t reference_spp = 4096;
    int64_t min_patches = 250;  // radiosity ladder, doubling
    int64_t max_patches = defaults::kRadiosityPatches;
    double radiosity_tolerance = defaults::kRadiosityTolerance;
    uint64_t radiosity_spp = 64;  // camera rays per pixel through the solution (its footprint)
    uint64_t seed = defaults::kSeed;
    int threads = 0;
    int max_depth = defaults::kMaxDepth;
    // Path ladders, one per configuration; the first is the baseline of the equal-time ratios
    // and its sampler displays radiosity.
    std::vector<RenderConfig> configs = {RenderConfig{}};
    SppRange fit_spp;
    // Set when --fit-spp was given: then a ladder with fewer than two rungs in it is an error;
    // otherwise the fit falls back to the whole ladder (and says so).
    bool fit_spp_given = false;
    // --region X,Y,W,H: the errors of that rectangle too (a caustic, where methods differ most).
    std::optional<PixelRect> region;
};

// --region "X,Y,W,H" (pixels of the rendered image, W and H at least 1).
absl::StatusOr<PixelRect> ParseRegion(const std::string& text);

struct ConvergenceRow {
    Method method = Method::kPath;
    RenderConfig config;  // path rows; radiosity rows: the sampler of its display
    int64_t budget = 0;   // spp or patches
    double seconds = 0;
    ImageError error;
    // The image's own estimate of its relmse from its A/B halves (lf::EstimatedRelMse), to
    // compare with `error.relmse`; path images of 2 spp or more only.
    std::optional<double> estimated_relmse;
    std::optional<ImageError> region_error;  // with --region
};

// A configuration's ladder summed up over the rungs of its fit range.
struct ConfigSummary {
    RenderConfig config;
    SppRange fit;  // the rungs used: --fit-spp's, or the whole ladder when it holds fewer than two
    double relative_rmse_slope = 0;  // of log sqrt(relmse) against log seconds
    double rmse_slope = 0;           // of log rmse against log seconds
    // Of log rmse against log spp: the same as rmse_slope at a constant speed, and free of
    // timing noise (a machine whose load changes during the ladders bends the time axis).
    double rmse_spp_slope = 0;
    double samples_per_second = 0;  // over the fit range's rungs
    // At equal time (ErrorAtTime at ConvergenceResult::equal_time.to), and the typical ratio to
    // the first configuration over the equal-time range (MeanRatioOverTime); 1 for the first.
    double rmse_at_equal_time = 0, relmse_at_equal_time = 0;
    double rmse_ratio_at_end = 1, relmse_ratio_at_end = 1;
    double rmse_ratio_mean = 1, relmse_ratio_mean = 1;
    // With --region: the region's RMSE at equal time and its ratio to the first configuration's
    // (at the end of the common time range and as the geometric mean over it); NaN without.
    double region_rmse_at_equal_time = std::numeric_limits<double>::quiet_NaN();
    double region_rmse_ratio_at_end = std::numeric_limits<double>::quiet_NaN();
    double region_rmse_ratio_mean = std::numeric_limits<double>::quiet_NaN();
};

struct ConvergenceResult {
    std::vector<ConvergenceRow> rows;
    std::vector<ConfigSummary> configs;  // path ladders, in the options' order
    std::string fit_note;                // when a fit fell back to the whole ladder, why
    TimeRange equal_time;                // the times every configuration's fit range covers
    // Why there is no equal-time comparison (the ladders share no time: a short ladder whose
    // rungs timing noise scatters, or configurations of very different speed); then the
    // equal-time errors and ratios are NaN and the slopes and speeds still stand.
    std::string equal_time_note;
    double radiosity_slope = 0;  // of sqrt(relmse) against seconds, with radiosity rows
    double whitted_slope = 0;    // the same for whitted rows
    std::string reference;       // what the reference was, for the user
    double reference_rmse = 0;   // the reference's own error estimate (A/B), 0 if unknown
    std::string csv_path, png_path, summary_path;
    std::string reference_exr_path;  // the own reference, written for reuse with --reference
};

absl::StatusOr<ConvergenceResult> RunConvergence(const ConvergenceOptions& options);

// convergence.csv: a row per image; sampler and light_sampling were added at the end (the light
// strategy is empty for radiosity, the sampler there is its display's), then the --region errors
// (empty without it).
inline constexpr const char* kConvergenceCsvHeader =
    "method,budget,seconds,rmse,relmse,smape,estimated_relmse,sampler,light_sampling,region_rmse,"
    "region_relmse";
// summary.csv: a row per ladder configuration (ConfigSummary); its method last.
inline constexpr const char* kSummaryCsvHeader =
    "sampler,light_sampling,fit_from_spp,fit_to_spp,relative_rmse_slope,rmse_slope,"
    "samples_per_second,equal_time_from,equal_time_to,rmse_at_equal_time,relmse_at_equal_time,"
    "rmse_ratio_at_end,rmse_ratio_mean,relmse_ratio_at_end,relmse_ratio_mean,rmse_spp_slope,"
    "region_rmse_at_equal_time,region_rmse_ratio_at_end,region_rmse_ratio_mean,method";

// The row's estimated_relmse as a CSV field: "" when there is none.
std::string EstimatedRelMseField(const ConvergenceRow& row);
// The CSV's region_rmse and region_relmse fields: ",," less the commas when there is none.
std::string RegionFields(const ConvergenceRow& row);
// The CSV's light_sampling field: the strategy of the methods that sample lights (path,
// whitted), empty for radiosity.
const char* LightSamplingField(const ConvergenceRow& row);

}  // namespace lf
