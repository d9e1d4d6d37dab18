#include "lf/job/render_metadata.h"

#include "lf/version.h"

namespace lf {

ExrAttributes DescribeRender(const RenderMetadata& m) {
    return {
        {"lightfarm.version", std::string(kVersion)},
        {"lightfarm.sceneHash", m.scene_hash},
        {"lightfarm.method", m.method},
        {"lightfarm.spp", int(m.spp)},
        {"lightfarm.seed", std::to_string(m.seed)},
        {"lightfarm.maxDepth", m.max_depth},
        {"lightfarm.seconds", m.seconds},
        {"lightfarm.invalidSamples", std::to_string(m.stats.invalid_samples)},
        {"lightfarm.rays", std::to_string(m.stats.rays)},
        {"lightfarm.channels",
         std::string("R,G,B: mean radiance W m^-2 sr^-1 (box filter); A.*, B.*: means of the "
                     "even and odd samples; spp: samples per pixel")},
    };
}

absl::StatusOr<ErrorEstimates> AddErrorEstimates(const Image& image, ExrAttributes* attributes) {
    ErrorEstimates e;
    absl::StatusOr<double> estimated = EstimatedRelativeError(image);
    if (!estimated.ok()) return estimated.status();
    absl::StatusOr<VarianceAssessment> variance = AssessVariance(image);
    if (!variance.ok()) return variance.status();
    e.estimated_error = *estimated;
    e.variance = *variance;
    (*attributes)["lightfarm.estimatedError"] = e.estimated_error;
    (*attributes)["lightfarm.estimatedRelMse"] = e.variance.relmse;
    (*attributes)["lightfarm.estimatedMeanError"] = e.variance.mean_error;
    (*attributes)["lightfarm.highVariance"] = std::string(e.variance.high ? "yes" : "no");
    return e;
}

void AddAdaptiveAttributes(const AdaptiveSettings& settings, const AdaptiveReport& report,
                           ExrAttributes* attributes) {
    (*attributes)["lightfarm.targetError"] = settings.target_error;
    (*attributes)["lightfarm.timeLimit"] = settings.time_limit;
    (*attributes)["lightfarm.adaptive.worstTileError"] = report.worst_tile_error;
    (*attributes)["lightfarm.adaptive.tilesAboveTarget"] = report.tiles_above_target;
    (*attributes)["lightfarm.adaptive.timedOut"] = std::string(report.timed_out ? "yes" : "no");
    (*attributes)["lightfarm.adaptive.minSpp"] = int(report.min_spp);
    (*attributes)["lightfarm.adaptive.maxSpp"] = int(report.max_spp);
}

}  // namespace lf
