// The EXR header attributes that say how an image was made, the same for `lightfarm render`
// and the farm.
#pragma once

#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/core/image_error.h"
#include "lf/core/image_io.h"
#include "lf/job/adaptive_plan.h"

namespace lf {

struct RenderMetadata {
    std::string scene_hash;
    std::string method;  // "path"
    uint64_t spp = 0;
    uint64_t seed = 0;
    int max_depth = -1;
    double seconds = 0;
    RenderStats stats;
};

ExrAttributes DescribeRender(const RenderMetadata& metadata);

// What an image estimates of its own error, from its A/B halves: needs 2 samples per pixel.
struct ErrorEstimates {
    double estimated_error = 0;  // EstimatedRelativeError
    VarianceAssessment variance;
};
// Adds them as lightfarm.estimatedError, .estimatedRelMse, .estimatedMeanError, .highVariance.
absl::StatusOr<ErrorEstimates> AddErrorEstimates(const Image& image, ExrAttributes* attributes);

// lightfarm.targetError, .timeLimit and lightfarm.adaptive.*: how an adaptive render ended.
void AddAdaptiveAttributes(const AdaptiveSettings& settings, const AdaptiveReport& report,
                           ExrAttributes* attributes);

}  // namespace lf
