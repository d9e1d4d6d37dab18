// `lightfarm render`: a scene file to an EXR (and PNG preview) in this process.
#pragma once

#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/image_io.h"
#include "lf/kernels/tile_renderer.h"

namespace lf {

struct LocalRenderOptions {
    std::string scene_path;
    std::string exr_path;
    std::string png_path;  // empty: no preview
    RenderSettings render;
    int max_depth = -1;
    bool progress = true;
};

struct LocalRenderSummary {
    std::string job_id;
    RenderStats stats;
    double seconds = 0;
    int width = 0, height = 0;
};

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options);

// The header attributes that say how an image was made.
ExrAttributes DescribeRender(const std::string& scene_hash, const std::string& method,
                             const RenderSettings& settings, int max_depth,
                             const RenderOutput& output);

}  // namespace lf
