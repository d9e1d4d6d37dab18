// `lightfarm render`: a scene file to an EXR (and PNG preview) in this process, by path tracing
// or radiosity, through the farm's planner and merger (local_executor.h).
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "lf/kernels/radiosity.h"
#include "local_executor.h"

namespace lf {

struct LocalRenderOptions {
    std::string scene_path;
    std::string exr_path;
    std::string png_path;  // empty: no preview
    std::string method = "path";  // path | radiosity | auto
    RenderSettings render;
    int max_depth = -1;
    RadiosityOptions radiosity;
    bool progress = true;
};

struct LocalRenderSummary {
    std::string job_id;
    std::string method;
    RenderStats stats;
    double seconds = 0;
    int width = 0, height = 0;
};

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options);

}  // namespace lf
