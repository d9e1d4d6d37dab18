// The solid angle a triangle subtends from a point, and uniform sampling of that solid angle
// (Arvo 1995, "Stratified Sampling of Spherical Triangles"): a large emissive triangle seen from
// close by is then sampled with a density proportional to how much of the sky it covers, not to
// its area, which removes the 1/r^2 and cosine variance of area sampling.
//
// Use (next-event estimation on an emissive triangle v0 v1 v2 from the shading point p):
//   SphericalTriangle st(p, v0, v1, v2);
//   if (st.samplable()) { SphericalTriangleSample s = st.Sample(u);  // s.wi, s.point, s.pdf }
//   else { sample by area and convert the area density to solid angle as before }
// and for the MIS weight of a BSDF-sampled ray that hit the triangle, build the same
// SphericalTriangle and use st.Pdf() if st.samplable(), the area density otherwise: the choice
// depends only on (p, triangle), so both sides always agree. The density covers the triangle's
// full solid angle, whichever side faces p: a one-sided emitter seen from behind is the caller's
// to reject.
#pragma once

#include "lf/core/vec.h"

namespace lf {

// Solid angles outside [min, max] are left to area sampling. Below the minimum the triangle is a
// few milliradians across: area sampling is then within a fraction of a percent of uniform in
// solid angle, and Arvo's mapping would gain nothing. Above the maximum (99% of a hemisphere, the
// point nearly on the triangle) the mapping is ill-conditioned: sin(alpha) -> 0 in its divisor.
inline constexpr float kMinSphericalTriangleSolidAngle = 1e-4f;
inline constexpr float kMaxSphericalTriangleSolidAngle = 6.2f;

// Solid angle of the triangle v0 v1 v2 seen from p (Van Oosterom & Strackee 1983), accurate for
// tiny and for nearly hemispherical triangles alike; 0 when p lies in the triangle's plane or on
// a vertex, or the triangle is degenerate.
float TriangleSolidAngle(const Vec3& p, const Vec3& v0, const Vec3& v1, const Vec3& v2);

struct SphericalTriangleSample {
    Vec3 wi;        // unit, from the reference point towards the triangle
    Vec3 point;     // where the ray p + t * wi meets the triangle
    Vec2 b;         // its barycentrics (b1, b2): point = v0 + b1 (v1 - v0) + b2 (v2 - v0)
    float pdf = 0;  // per unit solid angle at p: 1 / solid angle
};

// The triangle projected on the unit sphere about p. Computed in double internally: Arvo's
// formulas subtract nearly equal cosines when the triangle is small. Construction is cheap for
// triangles that are far away (a conservative bound rules them out before any trigonometry), as
// it runs once per light sample and per MIS weight.
class SphericalTriangle {
  public:
    // min_solid_angle (at least kMinSphericalTriangleSolidAngle): below it samplable() is false;
    // a caller that samples by area below a higher threshold saves the trigonometry there.
    SphericalTriangle(const Vec3& p, const Vec3& v0, const Vec3& v1, const Vec3& v2,
                      float min_solid_angle = kMinSphericalTriangleSolidAngle);

    float solid_angle() const { return float(solid_angle_); }
    // Whether Sample and Invert may be used: the triangle is not degenerate as seen from p and
    // its solid angle is within [min_solid_angle, kMaxSphericalTriangleSolidAngle].
    bool samplable() const { return samplable_; }
    // 1 / solid angle if samplable(), else 0.
    float Pdf() const { return samplable_ ? float(1 / solid_angle_) : 0.0f; }

    // A direction uniform over the solid angle for u uniform in [0, 1)^2. Requires samplable().
    SphericalTriangleSample Sample(const Vec2& u) const;
    // The u for which Sample(u).wi == wi (wi unit, towards the triangle), clamped to [0, 1]^2;
    // lets a caller warp the sample space, e.g. by the cosine at p. Requires samplable().
    Vec2 Invert(const Vec3& wi) const;

  private:
    Vec3d p_, v0_, v1_, v2_;
    Vec3d a_, b_, c_;  // unit directions from p to v0, v1, v2
    // The spherical angle alpha at a, kept as its cosine and sine: Sample needs only those.
    double cos_alpha_ = 1, sin_alpha_ = 0;
    double solid_angle_ = 0;
    bool samplable_ = false;
};

}  // namespace lf
