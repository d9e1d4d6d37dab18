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

// The interior a path is in (a material index, or -1 outside every solid) after leaving a
// surface of material `index` in direction wi, having been in `medium`: a transmission through
// a solid transmitter's surface enters it (against the geometric normal, cos_i_ng < 0) or
// leaves it.
inline int InteriorAfter(int medium, int index, const Material& material, float cos_i_ng,
                         bool transmitted) {
    if (!transmitted || !HasInterior(material)) return medium;
    return cos_i_ng < 0 ? index : -1;
}

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
