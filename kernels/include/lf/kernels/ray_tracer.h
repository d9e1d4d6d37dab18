// The ray-tracing methods a job or local render names by string (JobSpec::method): the
// estimators built from the scene, the depth and the light strategy alone. Radiosity, which
// needs a solve first, is built elsewhere (lf/kernels/radiosity.h).
#pragma once

#include <memory>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/light_strategy.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiance.h"

namespace lf {

// True for the methods MakeRayTracer builds: "path" (PathTracer) and "whitted" (WhittedTracer).
bool IsRayTracingMethod(std::string_view method);

// The estimator for `method`, tracing `scene` (which must outlive it) to max_depth (negative:
// the method's unlimited) with next-event estimation under `strategy`. InvalidArgument naming
// the method for any other.
absl::StatusOr<std::unique_ptr<RadianceEstimator>> MakeRayTracer(std::string_view method,
                                                                 const EmbreeScene& scene,
                                                                 int max_depth,
                                                                 LightStrategy strategy);

}  // namespace lf
