// One image by any spp-budgeted Monte Carlo method (path, whitted, light, bdpt, ppm) at a given
// spp, not adaptive: what `converge` ladders and `plan` pilots render, through the same
// planners and mergers as `render` (local_executor.h), so their images are render's.
#pragma once

#include <cstdint>

#include "absl/status/statusor.h"
#include "lf/core/camera.h"
#include "lf/job/method_registry.h"
#include "lf/job/splat_settings.h"
#include "lf/kernels/embree_scene.h"
#include "lf/local/local_executor.h"

namespace lf {

struct MethodRenderSettings {
    int max_depth = defaults::kMaxDepth;
    uint64_t seed = defaults::kSeed;
    SamplerType sampler = defaults::kSampler;
    LightStrategy light_strategy = defaults::kLightStrategy;
    double clamp = 0;
    int threads = 0;
    int tile = defaults::kTile;
    PhotonSettings ppm;
};

// `spp` samples per pixel of `method` (light paths per pixel for light, photon passes for ppm),
// planned as `render` plans it by default. InvalidArgument naming the method for any other.
absl::StatusOr<RenderOutput> RenderWithMethod(Method method, const EmbreeScene& scene,
                                              const Camera& camera,
                                              const MethodRenderSettings& settings, uint64_t spp);

}  // namespace lf
