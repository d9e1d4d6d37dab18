// What a light BVH knows of an emitter (Conty Estevez & Kulla 2018, "Importance Sampling of Many
// Lights with Adaptive Tree Splitting"; pbrt-v4's LightBounds): where it is, how much it emits,
// and in which directions; and from that a conservative estimate of its importance at a shading
// point.
//
// The normal cone: every emitting normal lies within theta_o of `axis`, and light leaves each
// normal within theta_e of it (pi/2 for a Lambertian face). Power `phi` may be in any unit
// common to all lights (watts, or the luminance of the radiance times the same factors): only
// ratios matter. Infinite lights (environment, directional) have no bounds; keep them out.
#pragma once

#include "lf/core/vec.h"

namespace lf {

struct LightBounds {
    Vec3 lower, upper;       // axis-aligned box holding the emitter; lower <= upper
    float phi = 0;           // emitted power; a light of no power is never sampled
    Vec3 axis{0, 0, 1};      // unit
    float cos_theta_o = 1;   // cos of the normals' spread about axis; -1: every direction
    float cos_theta_e = 0;   // cos of the emission's spread about each normal
    bool two_sided = false;  // emits on both sides of each normal (the cone and its mirror)

    // An upper bound, up to a factor common to all lights, of the irradiance the emitter can
    // send to p: phi / d^2 times the cosines at the emitter and at p, each taken at its most
    // favourable angle over the box. Zero only where no part of the emitter can light p (p
    // behind a one-sided emitter or outside a spot's cone, beyond the box's angular extent).
    // n: p's surface normal (unit; both sides count, for transmission), or zero for a point in
    // a volume. Finite: clamped to the largest float.
    float Importance(const Vec3& p, const Vec3& n) const;
};

// Bounds of both emitters: the box and the normal cone that hold both, the sum of powers.
LightBounds Union(const LightBounds& a, const LightBounds& b);

// Bounds of the common emitter kinds. `radiance` and `intensity` are scalars: use the same
// reduction of colour (e.g. luminance) for every light.
// A Lambertian triangle of the given radiance: phi = pi L area (twice that if two-sided).
LightBounds TriangleLightBounds(const Vec3& v0, const Vec3& v1, const Vec3& v2, float radiance,
                                bool two_sided);
// A Lambertian sphere: phi = pi L 4 pi r^2, normals in every direction.
LightBounds SphereLightBounds(const Vec3& center, float radius, float radiance);
// A point light: phi = 4 pi I.
LightBounds PointLightBounds(const Vec3& position, float intensity);
// A spot light (pointing along the unit `direction`) with full intensity I within the inner
// angle and none beyond the outer: phi = 4 pi I as for a point light, so that a spot and a point
// light of one intensity weigh the same where the spot shines; theta_o = inner angle, theta_e =
// outer - inner.
LightBounds SpotLightBounds(const Vec3& position, const Vec3& direction, float intensity,
                            float cos_inner, float cos_outer);

}  // namespace lf
