// `lightfarm render`: a scene file to an EXR (and PNG preview) in this process, by path tracing
// or radiosity, through the farm's planner and merger (local_executor.h).
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/kernels/radiosity.h"
#include "lf/local/local_executor.h"

namespace lf {

struct LocalRenderOptions {
    std::string scene_path;
    std::string exr_path;
    std::string png_path;         // empty: no preview
    std::string method = "path";  // path | radiosity | auto
    RenderSettings render;
    AdaptiveSettings adaptive;  // used when a target error or a time limit is set
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
    double estimated_error = -1;   // relative, from A/B; -1 below 2 samples per pixel
    double estimated_relmse = -1;  // EstimatedRelMse; -1 below 2 samples per pixel
    bool high_variance = false;
    bool adaptive = false;
    AdaptiveReport adaptive_report;
};

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options);

// The method for `requested` (path, radiosity or auto) and, in *why, the reason. `auto`:
// radiosity models exactly the scenes it can (all Lambertian, no spheres) and is
// view-independent; everything else needs the path tracer.
absl::StatusOr<std::string> ChooseMethod(const Scene& scene, const std::string& requested,
                                         std::string* why);

}  // namespace lf
