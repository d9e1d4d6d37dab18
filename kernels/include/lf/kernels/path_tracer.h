// Unidirectional path tracing of the full rendering equation: next-event estimation with
// multiple importance sampling (power heuristic) for area lights and the lights at infinity
// (environment, sun disks), which rays that leave the scene see; next-event estimation for
// delta lights, BSDF sampling at every vertex and Russian roulette on the path throughput.
// BSDFs are evaluated in the shading frame at each hit (lf/kernels/shading.h: vertex normals,
// normal maps, textures) while the geometric normal decides sides. Scenes with participating
// media (absorbing solids included) take VolPathTracer instead.
#pragma once

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/radiance.h"

namespace lf {

// The most bounces of an "unlimited" path. Roulette ends paths long before this unless a
// reflectance of 1 keeps their throughput at 1; then the cap bounds the work and the cut paths
// are counted in RenderStats::truncated_paths. At albedo 0.999 a path outlives it with
// probability e^-65.
inline constexpr int kMaxPathDepth = 1 << 16;

class PathTracer : public RadianceEstimator {
  public:
    // max_depth: the most bounces a path may take; negative means unlimited (roulette, and
    // kMaxPathDepth). strategy: how next-event estimation picks and samples lights.
    PathTracer(const EmbreeScene& scene, int max_depth,
               LightStrategy strategy = LightStrategy::kBvh);

    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override;
    const EmbreeScene& geometry() const override { return scene_; }

  private:
    const EmbreeScene& scene_;
    LightSampler lights_;
    int max_depth_;
};

}  // namespace lf
