// `lightfarm converge`: the trade between time and accuracy, measured. Renders a ladder of
// budgets per method (samples per pixel for the path tracer, patch counts for radiosity),
// compares each image with a reference and writes convergence.csv and a log-log plot of relative
// RMSE against time with the fitted slope per method (docs/convergence.md).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/image_error.h"
#include "lf/core/scene_loader.h"
#include "lf/job/settings.h"

namespace lf {

struct ConvergenceOptions {
    std::string scene_path;
    std::string out_dir;
    std::string reference_path;   // empty: render our own path-traced reference
    std::string method = "both";  // path | radiosity | both
    int resolution = 0;           // image width, height keeps the aspect; 0: the scene's
    SceneOptions scene;           // --camera; --resolution WxH (then `resolution` is 0)
    uint64_t max_spp = 256;       // path ladder 1, 2, 4, ... up to this
    uint64_t reference_spp = 4096;
    int64_t min_patches = 250;  // radiosity ladder, doubling
    int64_t max_patches = defaults::kRadiosityPatches;
    double radiosity_tolerance = defaults::kRadiosityTolerance;
    uint64_t radiosity_spp = 64;  // camera rays per pixel through the solution (its footprint)
    uint64_t seed = defaults::kSeed;
    int threads = 0;
    int max_depth = defaults::kMaxDepth;
    SamplerType sampler = defaults::kSampler;  // of the ladder, the own reference, radiosity
};

struct ConvergenceRow {
    std::string method;
    int64_t budget = 0;  // spp or patches
    double seconds = 0;
    ImageError error;
    // The image's own estimate of its relmse from its A/B halves (lf::EstimatedRelMse), to
    // compare with `error.relmse`; path images of 2 spp or more only.
    std::optional<double> estimated_relmse;
};

struct ConvergenceResult {
    std::vector<ConvergenceRow> rows;
    std::map<std::string, double> slopes;  // of sqrt(relmse) against seconds, per method
    std::string reference;                 // what the reference was, for the user
    double reference_rmse = 0;             // the reference's own error estimate (A/B), 0 if unknown
    std::string csv_path, png_path;
};

absl::StatusOr<ConvergenceResult> RunConvergence(const ConvergenceOptions& options);

// The row's estimated_relmse as a CSV field: "" when there is none.
std::string EstimatedRelMseField(const ConvergenceRow& row);

}  // namespace lf
