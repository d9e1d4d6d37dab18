#include "lf/kernels/ray_tracer.h"

#include "absl/strings/str_cat.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/whitted.h"

namespace lf {

bool IsRayTracingMethod(std::string_view method) { return method == "path" || method == "whitted"; }

absl::StatusOr<std::unique_ptr<RadianceEstimator>> MakeRayTracer(std::string_view method,
                                                                 const EmbreeScene& scene,
                                                                 int max_depth,
                                                                 LightStrategy strategy) {
    if (method == "path") return std::make_unique<PathTracer>(scene, max_depth, strategy);
    if (method == "whitted") return std::make_unique<WhittedTracer>(scene, max_depth, strategy);
    return absl::InvalidArgumentError(absl::StrCat("method \"", std::string(method),
                                                   "\": not a ray-tracing method (path, whitted)"));
}

}  // namespace lf
