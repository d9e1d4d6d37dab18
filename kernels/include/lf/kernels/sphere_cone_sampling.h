// Sampling a spherical emitter as seen from a point: from outside, uniformly over the cone of
// directions the sphere subtends (every sample lands on the visible cap, and the density is
// constant over it), from inside (or on it), uniformly by area. Area sampling from outside wastes
// the half of the samples that fall on the far side and weighs the rest by cos / r^2.
//
// Use (next-event estimation on an emissive sphere from the shading point p):
//   if (auto s = SampleSphereCone(p, center, radius, u)) {
//       SurfacePoint sp = embree_scene.SpherePoint(sphere, s->normal);  // or s->point directly
//       ... s->wi, s->pdf (per solid angle) ...
//   }
// and for the MIS weight of a BSDF-sampled ray that hit the sphere at `hit`:
//   SphereConePdf(p, center, radius, hit). Both take the same inside/outside decision.
#pragma once

#include <optional>

#include "lf/core/vec.h"

namespace lf {

struct SphereConeSample {
    Vec3 point;     // on the sphere, where the ray p + t * wi first meets it (from outside)
    Vec3 normal;    // unit, outward at point: the direction from the centre
    Vec3 wi;        // unit, from p to point
    float pdf = 0;  // per unit solid angle at p
};

// A point on the sphere for u uniform in [0, 1)^2; nullopt for a sphere of no size or a sample
// with no density (p exactly on the sampled point, or grazing it from inside).
std::optional<SphereConeSample> SampleSphereCone(const Vec3& p, const Vec3& center, float radius,
                                                 const Vec2& u);

// Density per unit solid angle at p with which SampleSphereCone yields `point` (a point on the
// sphere visible from p, e.g. where a ray from p first hits it): 1 / the cone's solid angle from
// outside, the area density converted to solid angle from inside.
float SphereConePdf(const Vec3& p, const Vec3& center, float radius, const Vec3& point);

}  // namespace lf
