#include "lf/local/method_factory.h"

#include "absl/strings/str_cat.h"
#include "lf/job/job_spec.h"
#include "lf/kernels/bdpt.h"
#include "lf/kernels/light_tracer.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/ppm.h"
#include "lf/kernels/vol_path_tracer.h"
#include "lf/kernels/whitted.h"

namespace lf {

absl::StatusOr<std::unique_ptr<RadianceEstimator>> MakeRayTracer(Method method,
                                                                 const EmbreeScene& scene,
                                                                 int max_depth,
                                                                 LightStrategy strategy) {
    switch (method) {
        case Method::kPath:
            if (scene.scene().HasMedia()) {
                return std::make_unique<VolPathTracer>(scene, max_depth, strategy);
            }
            return std::make_unique<PathTracer>(scene, max_depth, strategy);
        case Method::kWhitted:
            return std::make_unique<WhittedTracer>(scene, max_depth, strategy);
        default:
            return absl::InvalidArgumentError(absl::StrCat(
                "method \"", MethodName(method), "\": not a ray-tracing method (path, whitted)"));
    }
}

absl::StatusOr<std::unique_ptr<SplatRenderer>> MakeSplatRenderer(
    Method method, const EmbreeScene& scene, const Camera& camera,
    const SplatRenderSettings& settings) {
    if (absl::Status s = CheckMethodTakesFilter(method, camera.filter()); !s.ok()) return s;
    switch (method) {
        case Method::kLight:
            return std::make_unique<LightTracer>(scene, camera, settings);
        case Method::kBdpt:
            return std::make_unique<BdptRenderer>(scene, camera, settings);
        case Method::kPpm: {
            absl::StatusOr<std::unique_ptr<PpmRenderer>> ppm =
                PpmRenderer::Create(scene, camera, settings);
            if (!ppm.ok()) return ppm.status();
            return std::unique_ptr<SplatRenderer>(std::move(*ppm));
        }
        default:
            return absl::InvalidArgumentError(
                absl::StrCat("method ", MethodName(method),
                             ": no frame renderer (splatting methods: light, bdpt, ppm)"));
    }
}

SplatRenderSettings SplatRenderSettingsOf(const JobSpec& spec) {
    return SplatRenderSettingsOf<SplatRenderSettings>(spec.max_depth, spec.seed, spec.sampler,
                                                      spec.clamp, spec.light_strategy, spec.ppm);
}

absl::StatusOr<RadiosityOptions> RadiosityOptionsOf(const RadiositySettings& settings,
                                                    double target_error) {
    if (absl::Status s = CheckHierarchicalSolver(settings); !s.ok()) return s;
    absl::StatusOr<RadiosityOptions> options =
        MakeRadiosityOptions(settings.patches, settings.patch_size, settings.solver,
                             settings.tolerance, settings.max_iterations, settings.display);
    if (!options.ok()) return options.status();
    options->target_error = target_error;
    options->max_patches = settings.max_patches;
    options->hierarchical = settings.form == "hierarchical";
    options->link_error = settings.link_error;
    return options;
}

}  // namespace lf
