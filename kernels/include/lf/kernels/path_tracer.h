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
    // At the first hit, one sample of a Lambertian of albedo 1 times pi: next-event estimation
    // and a cosine-weighted direction whose radiance is this path tracer's own (MIS-weighted
    // where it meets an area light, up to max_depth bounces from the hit), so indirect light
    // counts. Unbiased; at least direct light with max_depth 0.
    std::optional<Rgb> Irradiance(const Ray& ray, Sampler& sampler,
                                  RenderStats& stats) const override;

  private:
    // Where a path's radiance is gathered from: a camera ray (sees emission with full weight),
    // or a ray BSDF-sampled at a vertex at depth - 1 with pdf prev_pdf.
    struct PathStart {
        int depth = 0;
        bool delta_bounce = true;
        float prev_pdf = 0;
        Vec3 prev_p, prev_n;
    };
    Rgb Trace(const Ray& ray, const PathStart& start, Sampler& sampler, RenderStats& stats) const;

    const EmbreeScene& scene_;
    LightSampler lights_;
    int max_depth_;
};

}  // namespace lf
