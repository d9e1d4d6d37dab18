// Every emitter of a scene, sampled for next-event estimation: emissive triangles and spheres
// (area lights, uniform by area) and point lights. A light is picked with probability
// proportional to its power, so a tiny bright emitter gets the samples it needs.
#pragma once

#include <optional>
#include <vector>

#include "lf/kernels/embree_scene.h"

namespace lf {

struct LightSample {
    Rgb radiance;        // L_e arriving at the reference point (intensity / r^2 for points)
    SurfacePoint point;  // on the light
    Vec3 wi;             // unit, from the reference point to the light
    float pdf = 0;       // solid angle density times the pick probability; for a point light
                         // just the pick probability
    bool delta = false;  // point light: not reachable by BSDF sampling
};

class LightSampler {
  public:
    explicit LightSampler(const EmbreeScene& scene);

    bool empty() const { return lights_.empty(); }
    size_t size() const { return lights_.size(); }

    std::optional<LightSample> Sample(const Vec3& ref, float u_pick, const Vec2& u) const;

    // Density, per solid angle at `ref`, with which Sample would have produced `hit` (an
    // emitter hit by a BSDF-sampled ray); used for multiple importance sampling.
    float Pdf(const Vec3& ref, const SurfaceHit& hit) const;

  private:
    enum class Kind { kTriangle, kSphere, kPoint };
    struct Light {
        Kind kind;
        int index;      // mesh (triangle) / sphere / point light
        int primitive;  // triangle within the mesh
        float area;
    };

    int LightIndex(const SurfaceHit& hit) const;

    const EmbreeScene& scene_;
    std::vector<Light> lights_;
    std::vector<float> pmf_;                        // pick probability per light
    std::vector<float> cdf_;                        // its running sum, cdf_.back() == 1
    std::vector<std::vector<int>> triangle_light_;  // per mesh, per triangle: light or -1
    std::vector<int> sphere_light_;                 // per sphere: light or -1
};

}  // namespace lf
