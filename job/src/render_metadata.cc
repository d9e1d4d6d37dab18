#include "lf/job/render_metadata.h"

#include "lf/version.h"

namespace lf {

namespace {

std::string YesNo(bool b) { return b ? "yes" : "no"; }

ExrAttributes DescribeMethod(const RenderMetadata& m) {
    return {
        {"lightfarm.version", std::string(kVersion)},
        {"lightfarm.sceneHash", m.scene_hash},
        {"lightfarm.method", m.method},
        {"lightfarm.spp", int(m.spp)},
        {"lightfarm.seed", std::to_string(m.seed)},
        {"lightfarm.maxDepth", m.max_depth},
        {"lightfarm.seconds", m.seconds},
        {"lightfarm.invalidSamples", std::to_string(m.stats.invalid_samples)},
        {"lightfarm.truncatedPaths", std::to_string(m.stats.truncated_paths)},
        {"lightfarm.rays", std::to_string(m.stats.rays)},
        {"lightfarm.channels",
         std::string("R,G,B: mean radiance W m^-2 sr^-1 (box filter); A.*, B.*: means of the "
                     "even and odd samples; spp: samples per pixel")},
    };
}

absl::StatusOr<ErrorEstimates> AddErrorEstimates(const Image& image, ExrAttributes& attributes) {
    ErrorEstimates e;
    absl::StatusOr<double> estimated = EstimatedRelativeError(image);
    if (!estimated.ok()) return estimated.status();
    absl::StatusOr<VarianceAssessment> variance = AssessVariance(image);
    if (!variance.ok()) return variance.status();
    e.estimated_error = *estimated;
    e.variance = *variance;
    attributes["lightfarm.estimatedError"] = e.estimated_error;
    attributes["lightfarm.estimatedRelMse"] = e.variance.relmse;
    attributes["lightfarm.estimatedMeanError"] = e.variance.mean_error;
    attributes["lightfarm.highVariance"] = YesNo(e.variance.high);
    return e;
}

void AddAdaptiveAttributes(const AdaptiveSettings& settings, const AdaptiveReport& report,
                           ExrAttributes& attributes) {
    attributes["lightfarm.targetError"] = settings.target_error;
    attributes["lightfarm.timeLimit"] = settings.time_limit;
    attributes["lightfarm.adaptive.worstTileError"] = report.worst_tile_error;
    attributes["lightfarm.adaptive.tilesAboveTarget"] = report.tiles_above_target;
    attributes["lightfarm.adaptive.timedOut"] = YesNo(report.timed_out);
    attributes["lightfarm.adaptive.minSpp"] = int(report.min_spp);
    attributes["lightfarm.adaptive.maxSpp"] = int(report.max_spp);
}

void AddRadiosityAttributes(const RenderMetadata& m, ExrAttributes& attributes) {
    const RadiositySettings& s = m.radiosity_settings;
    attributes["lightfarm.radiosity.solver"] = s.solver;
    attributes["lightfarm.radiosity.tolerance"] = s.tolerance;
    attributes["lightfarm.radiosity.display"] = s.display;
    if (!m.radiosity) return;
    const RadiosityFigures& r = *m.radiosity;
    attributes["lightfarm.radiosity.patches"] = std::to_string(r.patches);
    attributes["lightfarm.radiosity.unknowns"] = std::to_string(r.unknowns);
    attributes["lightfarm.radiosity.patchSize"] = r.patch_size;
    attributes["lightfarm.radiosity.iterations"] = r.iterations;
    attributes["lightfarm.radiosity.residual"] = r.residual;
    attributes["lightfarm.radiosity.loaded"] = YesNo(r.loaded);
    attributes["lightfarm.radiosity.formFactorSeconds"] = r.form_factor_seconds;
    attributes["lightfarm.radiosity.solveSeconds"] = r.solve_seconds;
    attributes["lightfarm.radiosity.estimatedError"] = r.estimated_error;
    attributes["lightfarm.radiosity.meanEstimatedError"] = r.mean_estimated_error;
    // The one --target-error bounds both errors: the mesh's and the display's sampling.
    if (const double target = m.adaptive_settings.target_error; target > 0) {
        attributes["lightfarm.radiosity.targetError"] = target;
        attributes["lightfarm.radiosity.refinePasses"] = r.refine_passes;
        attributes["lightfarm.radiosity.coarsePatches"] = std::to_string(r.coarse_patches);
        attributes["lightfarm.radiosity.budgetReached"] = YesNo(r.budget_reached);
        attributes["lightfarm.radiosity.finestAboveTarget"] = std::to_string(r.finest_above_target);
    }
}

}  // namespace

absl::StatusOr<RenderDescription> DescribeRender(const RenderMetadata& m, const Image& image,
                                                 bool complete) {
    RenderDescription d;
    d.attributes = DescribeMethod(m);
    if (!m.camera.empty()) d.attributes["lightfarm.camera"] = m.camera;
    // An adaptive render's first pass gives every pixel at least 2 samples (it is even).
    const uint64_t fewest_spp = m.adaptive ? m.adaptive->min_spp : m.spp;
    if (complete && fewest_spp >= 2) {
        absl::StatusOr<ErrorEstimates> e = AddErrorEstimates(image, d.attributes);
        if (!e.ok()) return e.status();
        d.estimates = *e;
    }
    if (m.adaptive) AddAdaptiveAttributes(m.adaptive_settings, *m.adaptive, d.attributes);
    if (m.method == "radiosity") AddRadiosityAttributes(m, d.attributes);
    return d;
}

}  // namespace lf
