// Every emitter of a scene, sampled for next-event estimation: emissive triangles and spheres
// (area lights, uniform by area, from the back too when two-sided), the delta lights (point,
// spot with smoothstep or KHR_lights_punctual falloff, directional) and the lights at infinity
// that BSDF-sampled rays can also reach: sun disks (directional lights with an angular
// diameter, uniform in their cone) and the environment.
//
// Two strategies (LightStrategy):
// - kPower: a light is picked with probability proportional to its power, so a tiny bright
//   emitter gets the samples it needs; triangles and spheres are sampled uniformly by area.
// Two consecutive triangles of a mesh that form a rectangle (a quad light, the Cornell box's
// lamp) are one light under both strategies: by area, that is the same as picking one of the two
// by power; by solid angle, one spherical rectangle instead of a pick and a spherical triangle.
// - kBvh (the default): the lights at infinity and directional lights keep their power
//   probabilities (as one group, so EscapedPdf is the same under both strategies), and the
//   finite lights (triangles, spheres, point and spot lights) share the rest, chosen among by a
//   light BVH (lf/kernels/light_bvh.h) by their importance at the shading point and normal.
//   Triangles and rectangles that subtend a solid angle worth it are sampled in it (spherical
//   triangles and rectangles, lf/kernels/spherical_triangle.h, spherical_rectangle.h; warped by
//   the receiver's cosine as in pbrt-v4 when there is a normal), the others by area; spheres
//   within their visible cone
//   (lf/kernels/sphere_cone_sampling.h). Pdf takes the same decisions, which depend only on
//   the reference point, its normal and the light.
#pragma once

#include <optional>
#include <vector>

#include "lf/core/light_strategy.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/environment_emitter.h"
#include "lf/kernels/light_bvh.h"
#include "lf/kernels/light_list.h"
#include "lf/kernels/spherical_rectangle.h"

namespace lf {

struct LightSample {
    Rgb radiance;        // L_e arriving at the reference point; for delta lights the value that
                         // times the cosine is the irradiance: intensity / r^2 (point, spot),
                         // the irradiance itself (directional)
    SurfacePoint point;  // on the light; for lights at infinity a point beyond the scene
    // A light at infinity (sky, sun disk, directional light): `point` only stands for it, so a
    // medium that extends past the scene attenuates the shadow ray beyond it too.
    bool at_infinity = false;
    Vec3 wi;             // unit, from the reference point to the light
    float pdf = 0;       // solid angle density times the pick probability; for a delta light
                         // just the pick probability
    bool delta = false;  // point, spot, directional: not reachable by BSDF sampling
    // Which emitter of the scene this is, for estimators that weigh the sample with another
    // sampler's densities (BDPT, via EmissionSampler::LightOf): the sphere (Scene::spheres) a
    // sphere light's point lies on, or the index of the point, spot or directional light in its
    // Scene list; -1 otherwise. Triangles carry point.mesh and point.primitive; the lights at
    // infinity (sun disks, environment) are weighed as one and name none.
    int sphere = -1, point_light = -1, spot_light = -1, directional_light = -1;
};

class LightSampler {
  public:
    // A scene whose light bounds the BVH refuses (powers beyond float) falls back to kPower,
    // with a warning.
    explicit LightSampler(const EmbreeScene& scene, LightStrategy strategy = LightStrategy::kBvh);

    bool empty() const { return lights_.empty(); }
    size_t size() const { return lights_.size(); }
    LightStrategy strategy() const { return strategy_; }

    // A light sample for the reference point `ref` with (shading) normal `n`, unit, or zero in a
    // volume; kPower ignores n. Moving emitters are where they are at `time` (Ray::time).
    std::optional<LightSample> Sample(const Vec3& ref, const Vec3& n, float u_pick, const Vec2& u,
                                      float time) const;

    // Light i (of size()) when it is a delta light (point, spot, directional without a
    // diameter), as Sample gives it at `ref` but with pdf 1; nullopt for the others: for
    // estimators that sum every delta light instead of picking one (lf/kernels/whitted.h).
    bool IsDeltaLight(size_t i) const;
    std::optional<LightSample> SampleDeltaLight(size_t i, const Vec3& ref, float time) const;

    // Density, per solid angle at `ref`, with which Sample(ref, n, ...) would have produced
    // `hit` (an emitter hit by a BSDF-sampled ray, at its time); used for multiple importance
    // sampling.
    float Pdf(const Vec3& ref, const Vec3& n, const SurfaceHit& hit) const;

    // Radiance of the lights at infinity (sun disks, environment) arriving along a ray that
    // leaves the scene in direction w (unit), and the density per solid angle with which Sample
    // would have produced w: what a BSDF-sampled ray that hits nothing sees, and its MIS weight.
    Rgb EscapedRadiance(const Vec3& w) const;
    float EscapedPdf(const Vec3& w) const;

  private:
    enum class Kind {
        kTriangle,
        kRectangle,
        kSphere,
        kPoint,
        kSpot,
        kDirectional,
        kSun,
        kEnvironment
    };
    struct Light {
        Kind kind;
        // mesh (triangle, rectangle) / sphere / point, spot, directional light / sun disk
        int index;
        int primitive;  // triangle within the mesh; a rectangle's: its entry in rectangles_
        float area;
        bool two_sided;  // area lights: emission leaves the back face too
    };
    // Two triangles of one mesh forming the rectangle corner + s ex + t ey, s, t in [0, 1].
    // Per triangle, its first vertex and the dual vectors of its edges: the barycentrics of a
    // point q in the plane are (Dot(q - origin, dual1), Dot(q - origin, dual2)).
    struct Rectangle {
        RectangleFrame frame;
        struct Half {
            int primitive;
            Vec3 origin, dual1, dual2;
        };
        Half halves[2];
    };
    // A spot light's cone (its axis at a time: EmbreeScene::SpotLightAt): with c = 1 - cos(angle
    // to the axis) and t = clamp((one_minus_cos_outer - c) * inv_width, 0, 1) its falloff is
    // t^2 (KHR_lights_punctual) or t^2 (3 - 2 t) (smoothstep).
    struct SpotCone {
        float one_minus_cos_outer, inv_width;
        bool smooth;
    };
    // The rectangle triangles t and t + 1 of mesh m form, if they do.
    static std::optional<Rectangle> FormRectangle(const EmbreeScene& es, int m, int t);
    int LightIndex(const SurfaceHit& hit) const;
    // A point on area light `light` (triangle or sphere) for u, with its density per solid
    // angle at ref (normal n, for the cosine warp of large triangles), not yet times the pick
    // probability.
    std::optional<LightSample> SampleArea(const Light& light, const Vec3& ref, const Vec3& n,
                                          const Vec2& u, float time) const;
    // The density with which SampleArea yields `hit` on area light `light` from ref.
    float AreaPdf(const Light& light, const Vec3& ref, const Vec3& n, const SurfaceHit& hit) const;
    // The point at (s, t) of rectangle light `light`, on whichever of its triangles holds it.
    SurfacePoint RectanglePoint(const Light& light, const Vec2& st) const;
    std::optional<LightSample> SampleDelta(const Light& light, const Vec3& ref, float time) const;
    // A direction towards a sun disk (uniform in its cone) or the environment (by its map).
    std::optional<Vec3> SampleInfiniteDirection(const Light& light, const Vec2& u) const;
    // Where a shadow ray from ref towards a light at infinity in direction wi ends.
    Vec3 InfinitePoint(const Vec3& ref, const Vec3& wi) const;

    const EmbreeScene& scene_;
    LightStrategy strategy_;
    std::vector<Light> lights_;  // the finite lights first: [0, finite_count_)
    size_t finite_count_ = 0;
    // kPower: pick probability per light. kBvh: the same for the lights at infinity; the finite
    // lights' sum is finite_pmf_, the BVH shares it.
    std::vector<float> pmf_;
    float finite_pmf_ = 0;
    LightBvh bvh_;            // kBvh: over lights_[0, finite_count_)
    std::vector<float> cdf_;  // its running sum, cdf_.back() == 1
    std::vector<Rectangle> rectangles_;
    std::vector<std::vector<int>> triangle_light_;  // per mesh, per triangle: light or -1
    std::vector<int> sphere_light_;                 // per sphere: light or -1
    std::vector<SpotCone> spot_cones_;              // per spot light
    std::vector<SunDisk> suns_;                     // per directional light with a diameter
    std::vector<float> sun_pmf_;                    // their pick probabilities
    std::optional<EnvironmentEmitter> environment_;
    float environment_pmf_ = 0;
    // Radius of a sphere about the render-space origin holding all geometry: shadow rays to
    // lights at infinity end beyond it.
    float scene_radius_ = 0;
};

}  // namespace lf
