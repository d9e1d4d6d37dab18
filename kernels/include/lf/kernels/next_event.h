// What the path tracer and photon mapping share at a surface vertex: the power heuristic, the
// interior a path enters or leaves, and one next-event estimate (a light sample, its shadow ray,
// its MIS weight against the BSDF and Beer's law on the way).
#pragma once

#include "lf/core/film.h"
#include "lf/core/rgb.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/shading.h"

namespace lf {

// Veach's power heuristic (beta = 2) of a sample from strategy a against strategy b; 1 when a's
// density overflows (a delta), 0 when neither can make the sample.
inline float PowerHeuristic(float pdf_a, float pdf_b) {
    const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    if (std::isinf(a)) return 1;
    return a + b > 0 ? a / (a + b) : 0;
}

// The media on either side of the surface `hit` lies on (its shape's).
const MediumInterface& InterfaceAt(const Scene& scene, const SurfaceHit& hit);

// The medium a path is in after crossing a surface of interface `mi` and geometric normal ng
// into direction w (any length), having been in `medium`: the side w points into, or `medium`
// unchanged when the shape has no interface. Only for paths that cross (transmit or pass an
// interface surface); a reflection stays where it was.
inline int MediumAfter(const MediumInterface& mi, int medium, const Vec3& ng, const Vec3& w) {
    if (!mi.has_interface) return medium;
    return Dot(w, ng) < 0 ? mi.interior : mi.exterior;
}
inline int MediumAfter(const Scene& scene, int medium, const SurfaceHit& hit, const Vec3& w) {
    return MediumAfter(InterfaceAt(scene, hit), medium, hit.n, w);
}

// The most interface surfaces one ray (a path's segment between two vertices, a shadow ray)
// crosses: beyond it the geometry is degenerate (coincident interfaces hit again and again) and
// the ray counts as blocked, so no ray loops for ever.
inline constexpr int kMaxInterfaceCrossings = 1024;

// Beer's law over `distance` (render space) of `medium`, 1 in vacuum (-1): the homogeneous
// absorbers (a solid's KHR_materials_volume attenuation) that the methods other than the path
// tracer take (lf/job/method_registry.h refuses them any other medium).
Rgb Attenuation(const EmbreeScene& scene, int medium, float distance);

// One light sample at `hit` (shading `sh`, the BSDF in the frame of sh.ns, wo_world the unit
// direction the path leaves towards) for a path of throughput `beta` inside `medium`: beta f
// Le |cos| w / pdf, with w the power heuristic against the BSDF's density (1 for delta
// lights), times Beer's law when the light is reached through a solid's interior; 0 when the
// sample is occluded or carries nothing. Counts its shadow ray in stats.rays. The BSDF must
// not be a delta (nothing to connect).
Rgb NextEventEstimate(const EmbreeScene& scene, const LightSampler& lights, const SurfaceHit& hit,
                      const Shading& sh, const Vec3& wo_world, const Bsdf& bsdf, int medium,
                      const Rgb& beta, float u_pick, const Vec2& u_light, RenderStats& stats);

}  // namespace lf
