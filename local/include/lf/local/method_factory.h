// The kernels of each render method (lf/job/method_registry.h), built from a job's settings: the
// one place local mode, the worker, `plan`, `converge` and `bench` construct a method's
// renderer, so one job gives one kernel configuration everywhere, hence the same bits.
#pragma once

#include <memory>

#include "absl/status/statusor.h"
#include "lf/core/camera.h"
#include "lf/core/light_strategy.h"
#include "lf/job/job_spec.h"
#include "lf/job/method_registry.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiance.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/splat_renderer.h"

namespace lf {

// The estimator of a tile method (path, whitted), tracing `scene` (which must outlive it) to
// max_depth (negative: the method's unlimited) with next-event estimation under `strategy`.
// InvalidArgument naming the method for any other.
absl::StatusOr<std::unique_ptr<RadianceEstimator>> MakeRayTracer(Method method,
                                                                 const EmbreeScene& scene,
                                                                 int max_depth,
                                                                 LightStrategy strategy);

// The renderer of a splatting method (light, bdpt, ppm) over `scene` seen through `camera` (both
// must outlive it). InvalidArgument naming the method for any other; FailedPrecondition when
// the method does not take the camera's pixel filter (CheckMethodTakesFilter) or the settings.
absl::StatusOr<std::unique_ptr<SplatRenderer>> MakeSplatRenderer(
    Method method, const EmbreeScene& scene, const Camera& camera,
    const SplatRenderSettings& settings);

// The splat kernel' settings of `spec` (SplatRenderSettingsOf).
SplatRenderSettings SplatRenderSettingsOf(const JobSpec& spec);

// The radiosity kernel's options for `settings`, refining the mesh to target_error (0: none).
// InvalidArgument for an unknown solver or display. Files, threads and cancellation are the
// caller's.
absl::StatusOr<RadiosityOptions> RadiosityOptionsOf(const RadiositySettings& settings,
                                                    double target_error);

}  // namespace lf
