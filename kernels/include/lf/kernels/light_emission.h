// The light end of a light path (pbrt-v4's Light::SampleLe / PDF_Le): a light picked by power,
// then a ray leaving it, with the densities light tracing, bidirectional path tracing and photon
// mapping need.
//
// - Area lights (emissive triangles, spheres): a point uniform by area (pdf_pos = 1 / area), a
//   direction cosine-weighted about the normal (pdf_dir = |cos| / pi); a two-sided emitter picks
//   either side with probability 1/2 (pdf_dir halves). Le is the material's emission times its
//   emission texture at the point.
// - Point lights: position delta (pdf_pos = 1, delta_pos), direction uniform on the sphere.
// - Spot lights: position delta, direction uniform in the outer cone; Le carries the falloff.
// - Lights at infinity (directional, sun disk, environment): a direction towards the light (the
//   delta direction, uniform in the sun's cone, by the environment map), then a point on the
//   disk of the scene's bounding sphere's radius R that is perpendicular to it and tangent to
//   the sphere on the light's side (pdf_pos = 1 / (pi R^2)); the ray travels away from the
//   light. A directional light's direction is a delta (delta_dir, pdf_dir = 1).
//
// Le's unit follows pbrt: radiance for area lights, suns and the environment; intensity
// (W/sr) for point and spot lights; irradiance for directional lights. In every case the
// emitted flux is E[Le |cos| / (pick pdf_pos pdf_dir)], with cos the angle between the ray
// and the emitter's normal (1 for point, spot and the lights at infinity, whose disk faces
// the ray).
//
// Light indices are this class's own (Sample returns one, LightOf maps a hit to one); they
// are not LightSampler's.
#pragma once

#include <optional>
#include <vector>

#include "lf/core/rgb.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/environment_emitter.h"
#include "lf/kernels/light_list.h"
#include "lf/kernels/lights.h"

namespace lf {

struct EmissionSample {
    int light = -1;      // the picked light
    SurfacePoint point;  // where the ray starts: on the emitter, or on the disk outside the scene
    Vec3 w;              // unit direction of travel, away from the light
    Rgb le;              // see the file comment for its unit
    float pick = 0;      // probability that the light was picked
    float pdf_pos = 0;   // area density of point (1 for a delta position)
    float pdf_dir = 0;   // solid-angle density of w given point (1 for a delta direction)
    bool delta_pos = false, delta_dir = false;
    // An area light: point lies on the emitter's surface (point.n its geometric normal), so a
    // camera can see it; false for point, spot and the lights at infinity.
    bool on_surface = false;
    int sphere = -1;  // sphere lights: the sphere (Scene::spheres) the point lies on

    // The ray that leaves the emitter, starting outside the point's error bound.
    Ray ray() const { return SpawnRay(point, w); }
};

// Densities of an emitted ray: pos per area, dir per solid angle.
struct EmissionPdf {
    float pos = 0, dir = 0;
};

class EmissionSampler {
  public:
    explicit EmissionSampler(const EmbreeScene& scene);

    bool empty() const { return lights_.empty(); }
    size_t size() const { return lights_.size(); }
    // Probability with which Sample picks `light`.
    float Pmf(int light) const { return picks_.pmf[size_t(light)]; }
    // Whether `light` is at infinity (directional, sun disk, environment): its rays start on the
    // disk outside the scene and its densities are per solid angle of direction.
    bool AtInfinity(int light) const {
        const Kind kind = lights_[size_t(light)].kind;
        return kind == Kind::kDirectional || kind == Kind::kSun || kind == Kind::kEnvironment;
    }
    // Radius of the sphere about the render-space origin that holds the scene: the disk the
    // lights at infinity emit from has this radius.
    float scene_radius() const { return scene_radius_; }

    // An emitted ray: u_pick picks the light, u_pos the point on it (lights at infinity: on the
    // disk), u_dir the direction (two-sided emitters: u_dir.x also picks the side). nullopt when
    // the sample carries no light (a cut-out of a textured emitter, outside a spot's cone, ...).
    // The ray leaves at `time` in the shutter (Ray::time), from where a moving emitter is then.
    std::optional<EmissionSample> Sample(float u_pick, const Vec2& u_pos, const Vec2& u_dir,
                                         float time) const;

    // The light a surface hit is on (an emissive triangle or sphere), or -1.
    int LightOf(const SurfaceHit& hit) const;
    // The light a LightSampler sample came from (its point's triangle or sphere, or its point,
    // spot or directional light), or -1 for the lights at infinity, which LightSampler weighs as
    // one (EscapedPdfLe gives their density).
    int LightOf(const LightSample& sample) const;

    // The densities (without the pick probability) with which Sample, having picked `light`,
    // would emit from point p (normal n: the surface's geometric normal for area lights, ignored
    // otherwise) in direction w (unit, away from the light). For a light at infinity p and n are
    // ignored and pos is 1 / (pi R^2); w must then be the direction of travel. Deltas: the
    // densities of the delta parts are 1 when w is the light's own direction, else 0.
    // A moving spot light's cone is the one of `time`.
    EmissionPdf PdfLe(int light, const Vec3& p, const Vec3& n, const Vec3& w, float time) const;

    // For a path vertex that escaped the scene travelling along -w (w unit, towards the sky):
    // pos = 1 / (pi R^2) and dir = the sum over the lights at infinity (not directional delta
    // lights) of pick probability times the density of emitting along -w, as pbrt-v4's BDPT
    // weighs an escaped vertex (its InfiniteLightDensity). The pick is included here.
    EmissionPdf EscapedPdfLe(const Vec3& w) const;

  private:
    enum class Kind { kTriangle, kSphere, kPoint, kSpot, kDirectional, kSun, kEnvironment };
    struct Light {
        Kind kind;
        int index;      // mesh, sphere, point, spot or directional light; sun: its entry in suns_
        int primitive;  // triangle within the mesh
        float area;     // area lights
        bool two_sided;
    };
    // A spot light's cone (SpotBandOf, as LightSampler's): with c = 1 - cos(angle to the axis),
    // the falloff is SpotBandFalloff(clamp((one_minus_cos_outer - c) * inv_width, 0, 1)). Its
    // position and axis at a time are EmbreeScene::SpotLightAt's.
    struct SpotCone {
        float one_minus_cos_outer, inv_width;
        bool smooth;
        Rgb intensity;
    };

    // An area light's point for u, with its normal and Le there (Le before the side test).
    SurfacePoint AreaPoint(const Light& light, const Vec2& u, float time) const;
    Rgb AreaEmission(const Light& light, const SurfacePoint& point) const;
    // 1 / the density by area of a point on `light` at `time`.
    float AreaAt(const Light& light, float time) const;
    // Direction density of a light at infinity for a ray travelling along w.
    float InfiniteDirPdf(const Light& light, const Vec3& w) const;

    const EmbreeScene& scene_;
    std::vector<Light> lights_;
    LightPickTable picks_;
    std::vector<std::vector<int>> triangle_light_;  // per mesh, per triangle: light or -1
    std::vector<int> sphere_light_;                 // per sphere: light or -1
    // The lights of the scene's point, spot and directional lights, by their index there.
    std::vector<int> point_light_, spot_light_, directional_light_;
    std::vector<SpotCone> spots_;  // per spot light
    std::vector<SunDisk> suns_;
    std::optional<EnvironmentEmitter> environment_;
    float scene_radius_ = 1;
};

}  // namespace lf
