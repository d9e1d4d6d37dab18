// Every emitter of a scene, sampled for next-event estimation: emissive triangles and spheres
// (area lights, uniform by area) and the delta lights: point, spot (KHR_lights_punctual's cone
// falloff) and directional. A light is picked with probability proportional to its power, so a
// tiny bright emitter gets the samples it needs.
#pragma once

#include <optional>
#include <vector>

#include "lf/kernels/embree_scene.h"

namespace lf {

struct LightSample {
    Rgb radiance;        // L_e arriving at the reference point; for delta lights the value that
                         // times the cosine is the irradiance: intensity / r^2 (point, spot),
                         // the irradiance itself (directional)
    SurfacePoint point;  // on the light; for a directional light a point beyond the scene
    Vec3 wi;             // unit, from the reference point to the light
    float pdf = 0;       // solid angle density times the pick probability; for a delta light
                         // just the pick probability
    bool delta = false;  // point, spot, directional: not reachable by BSDF sampling
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
    enum class Kind { kTriangle, kSphere, kPoint, kSpot, kDirectional };
    struct Light {
        Kind kind;
        int index;      // mesh (triangle) / sphere / point, spot or directional light
        int primitive;  // triangle within the mesh
        float area;
    };
    // A spot light's cone in render space, with KHR_lights_punctual's falloff
    // clamp(cos * scale + offset, 0, 1)^2.
    struct SpotCone {
        Vec3 direction;
        float scale, offset;
    };

    int LightIndex(const SurfaceHit& hit) const;
    std::optional<LightSample> SampleDelta(const Light& light, const Vec3& ref) const;

    const EmbreeScene& scene_;
    std::vector<Light> lights_;
    std::vector<float> pmf_;                        // pick probability per light
    std::vector<float> cdf_;                        // its running sum, cdf_.back() == 1
    std::vector<std::vector<int>> triangle_light_;  // per mesh, per triangle: light or -1
    std::vector<int> sphere_light_;                 // per sphere: light or -1
    std::vector<SpotCone> spot_cones_;              // per spot light
    // Radius of a sphere about the render-space origin holding all geometry: shadow rays to a
    // directional light end beyond it.
    float scene_radius_ = 0;
};

}  // namespace lf
