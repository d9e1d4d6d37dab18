// Uniform sampling of the solid angle a rectangle subtends from a point (Urena, Fajardo & King
// 2013, "An Area-Preserving Parametrization for Spherical Rectangles", as Cycles samples area
// lights): one step for a rectangular emitter such as the Cornell box's lamp, which otherwise is
// two emissive triangles, one to pick and then its spherical triangle to sample.
//
// Use (next-event estimation on a rectangle with corner c and orthogonal edges ex, ey from p):
//   const RectangleFrame frame(c, ex, ey);  // once per light
//   SphericalRectangle sr(p, frame);
//   if (sr.samplable()) { SphericalRectangleSample s = sr.Sample(u);  // s.point, s.uv, s.pdf }
//   else { sample by area }
// and for the MIS weight of a BSDF-sampled ray that hit it, the same SphericalRectangle's Pdf()
// if samplable(): the choice depends only on (p, rectangle), as for spherical triangles
// (lf/kernels/spherical_triangle.h, whose solid-angle limits apply here too).
#pragma once

#include "lf/core/vec.h"
#include "lf/kernels/spherical_triangle.h"

namespace lf {

struct SphericalRectangleSample {
    Vec3 wi;        // unit, from the reference point towards the rectangle
    Vec3 point;     // on the rectangle: c + uv.x ex + uv.y ey
    Vec2 uv;        // in [0, 1]^2
    float pdf = 0;  // per unit solid angle at p: 1 / solid angle
};

// A rectangle corner + s ex + t ey, s, t in [0, 1], ex and ey orthogonal, with what every
// SphericalRectangle of it needs: computed once per light rather than at every light sample,
// where the square roots and divisions cost a Cornell box a few percent of its render time.
struct RectangleFrame {
    RectangleFrame(const Vec3& corner, const Vec3& ex, const Vec3& ey);

    Vec3 corner, ex, ey;
    float ex_length = 0, ey_length = 0;
    Vec3 x, y, normal;  // unit: along ex, along ey, and their cross product
    Vec3 center;        // corner + (ex + ey) / 2
    float half_diagonal = 0;
};

// The rectangle projected on the unit sphere about p, in Urena et al.'s frame: x along ex, y
// along ey, z towards p's side, the rectangle at z = z0 < 0. In float, as Cycles does: the solid
// angle is a sum of four angles minus 2 pi, which loses about 1e-6 sr to rounding, a part in 1e-4
// of the smallest solid angle sampled (kMinSphericalTriangleSolidAngle); double would cost a
// Cornell box several percent of its render time.
class SphericalRectangle {
  public:
    // p on either side of the rectangle. min_solid_angle as for SphericalTriangle.
    SphericalRectangle(const Vec3& p, const RectangleFrame& rectangle,
                       float min_solid_angle = kMinSphericalTriangleSolidAngle);

    float solid_angle() const { return solid_angle_; }
    // Whether Sample and Invert may be used: p is off the rectangle's plane and the solid angle
    // is within [min_solid_angle, kMaxSphericalTriangleSolidAngle]. Far
    // rectangles are ruled out by a bound before any trigonometry.
    bool samplable() const { return samplable_; }
    // 1 / solid angle if samplable(), else 0.
    float Pdf() const { return samplable_ ? 1 / solid_angle_ : 0.0f; }

    // A direction uniform over the solid angle for u uniform in [0, 1)^2; u.x moves the point
    // along ex, u.y along ey. Requires samplable().
    SphericalRectangleSample Sample(const Vec2& u) const;
    // The u for which Sample(u).point == point (on the rectangle), clamped to [0, 1]^2; lets a
    // caller warp the sample space, e.g. by the cosine at p. Requires samplable().
    Vec2 Invert(const Vec3& point) const;

  private:
    // The sum of the spherical rectangle's angles at the edge x = x (from the edges y = y0 and
    // y = y1): k + the solid angle of the part with x0 <= x' <= x.
    float AngleSum(float x) const;

    Vec3 p_, corner_, ex_, ey_;
    Vec3 x_, y_;  // unit, along ex and ey
    float x0_ = 0, x1_ = 0, y0_ = 0, y1_ = 0, z0_ = 0;
    // The z components of the unit normals of the great circles through the edges y = y0 and
    // y = y1: (0, z0, -y0) / |.| and (0, -z0, y1) / |.|.
    float b0_ = 0, b1_ = 0;
    float k_ = 0;            // 2 pi minus the angles at the edge x = x0
    float solid_angle_ = 0;  // AngleSum(x1) - k_
    bool samplable_ = false;
};

}  // namespace lf
