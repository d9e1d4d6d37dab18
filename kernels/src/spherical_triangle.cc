#include "lf/kernels/spherical_triangle.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lf {
namespace {

// Van Oosterom & Strackee: tan(omega / 2) = |a.(b x c)| / (|a||b||c| + (a.b)|c| + (a.c)|b| +
// (b.c)|a|) for the vectors from the viewpoint to the vertices. atan2 keeps the quadrant, so
// solid angles above pi (a negative denominator) come out right.
double SolidAngle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const double la = Length(a), lb = Length(b), lc = Length(c);
    const double numerator = std::abs(Dot(a, Cross(b, c)));
    if (numerator == 0 || la == 0 || lb == 0 || lc == 0) return 0;
    const double denominator = la * lb * lc + Dot(a, b) * lc + Dot(a, c) * lb + Dot(b, c) * la;
    return 2 * std::atan2(numerator, denominator);
}

// The same for unit vectors, whose lengths need not be computed.
double UnitSolidAngle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const double numerator = std::abs(Dot(a, Cross(b, c)));
    if (numerator == 0) return 0;
    return 2 * std::atan2(numerator, 1 + Dot(a, b) + Dot(a, c) + Dot(b, c));
}

// An upper bound on the solid angle of the triangle d0 d1 d2 (vertices relative to the viewpoint)
// from its area A, its plane's distance h and a lower bound r_min on the distance to any of its
// points: the solid angle is the integral of cos / r^2 = h / r^3 over the triangle, at most
// A h / r_min^3 = |N . d0| / (2 r_min^3) for the normal N = (d1 - d0) x (d2 - d0). Infinite when
// the viewpoint may be within the triangle's bounding sphere. Costs two square roots and no
// trigonometry, so far triangles skip the rest.
double SolidAngleBound(const Vec3d& d0, const Vec3d& d1, const Vec3d& d2) {
    const Vec3d centroid = (d0 + d1 + d2) / 3.0;
    const double radius =
        std::sqrt(std::max({LengthSquared(d0 - centroid), LengthSquared(d1 - centroid),
                            LengthSquared(d2 - centroid)}));
    const double r_min = Length(centroid) - radius;
    if (!(r_min > 0)) return std::numeric_limits<double>::infinity();
    return 0.5 * std::abs(Dot(Cross(d1 - d0, d2 - d0), d0)) / (r_min * r_min * r_min);
}

// The component of v orthogonal to the unit vector w, normalised.
Vec3d Orthonormal(const Vec3d& v, const Vec3d& w) { return Normalize(v - w * Dot(v, w)); }

}  // namespace

float TriangleSolidAngle(const Vec3& p, const Vec3& v0, const Vec3& v1, const Vec3& v2) {
    const Vec3d pd(p);
    return float(SolidAngle(Vec3d(v0) - pd, Vec3d(v1) - pd, Vec3d(v2) - pd));
}

SphericalTriangle::SphericalTriangle(const Vec3& p, const Vec3& v0, const Vec3& v1, const Vec3& v2,
                                     float min_solid_angle)
    : p_(p), v0_(v0), v1_(v1), v2_(v2) {
    min_solid_angle = std::max(min_solid_angle, kMinSphericalTriangleSolidAngle);
    const Vec3d d0 = v0_ - p_, d1 = v1_ - p_, d2 = v2_ - p_;
    // Half the threshold leaves room for the rounding of the exact solid angle below, so the bound
    // only ever skips triangles that the exact test would reject too.
    if (SolidAngleBound(d0, d1, d2) < 0.5 * min_solid_angle) return;
    const double l0 = Length(d0), l1 = Length(d1), l2 = Length(d2);
    if (l0 == 0 || l1 == 0 || l2 == 0) return;
    a_ = d0 / l0;
    b_ = d1 / l1;
    c_ = d2 / l2;
    solid_angle_ = UnitSolidAngle(a_, b_, c_);
    if (!(solid_angle_ >= min_solid_angle && solid_angle_ <= kMaxSphericalTriangleSolidAngle)) {
        return;
    }
    // alpha is the angle between the planes through a, b and a, c: cos alpha is the cosine of
    // their normals, and |(a x b) x (a x c)| = |a . (b x c)| gives its sine without acos/asin.
    const Vec3d n_ab = Cross(a_, b_), n_ac = Cross(a_, c_);
    const double norms = std::sqrt(LengthSquared(n_ab) * LengthSquared(n_ac));
    if (norms == 0) return;
    cos_alpha_ = std::clamp(Dot(n_ab, n_ac) / norms, -1.0, 1.0);
    sin_alpha_ = std::abs(Dot(a_, Cross(b_, c_))) / norms;
    samplable_ = sin_alpha_ > 0;
}

SphericalTriangleSample SphericalTriangle::Sample(const Vec2& u) const {
    // Arvo's first step: the sub-triangle a b c' of area u0 * A, with c' on the arc a-c, from
    // the spherical law of cosines; q = cos of the arc a-c'.
    const double area = u.x * solid_angle_;
    const double sin_area = std::sin(area), cos_area = std::cos(area);
    const double cos_alpha = cos_alpha_, sin_alpha = sin_alpha_;
    // s and t are the sine and cosine of area - alpha.
    const double s = sin_area * cos_alpha - cos_area * sin_alpha;
    const double t = cos_area * cos_alpha + sin_area * sin_alpha;
    const double k1 = t - cos_alpha;
    const double k2 = s + sin_alpha * Dot(a_, b_);
    const double q = std::clamp(
        ((k2 * t - k1 * s) * cos_alpha - k2) / ((k2 * s + k1 * t) * sin_alpha), -1.0, 1.0);
    const Vec3d c_prime = a_ * q + Orthonormal(c_, a_) * std::sqrt(std::max(0.0, 1 - q * q));

    // Second step: along the arc b-c', with z = cos of the angle from b uniform in [cos bc', 1].
    const double z = 1 - u.y * (1 - Dot(c_prime, b_));
    const Vec3d w = b_ * z + Orthonormal(c_prime, b_) * std::sqrt(std::max(0.0, (1 - z) * (1 + z)));

    // The point the direction meets on the triangle (Moller-Trumbore), clamped into it against
    // the last bits of rounding.
    const Vec3d e1 = v1_ - v0_, e2 = v2_ - v0_;
    const Vec3d s1 = Cross(w, e2);
    const double divisor = Dot(s1, e1);
    double b1 = 1.0 / 3, b2 = 1.0 / 3;
    if (divisor != 0) {
        const Vec3d d = p_ - v0_;
        b1 = std::clamp(Dot(d, s1) / divisor, 0.0, 1.0);
        b2 = std::clamp(Dot(w, Cross(d, e1)) / divisor, 0.0, 1.0);
        if (b1 + b2 > 1) {
            const double sum = b1 + b2;
            b1 /= sum;
            b2 /= sum;
        }
    }
    const Vec3d point = v0_ + e1 * b1 + e2 * b2;
    return {Normalize(Vec3(w)), Vec3(point), Vec2(float(b1), float(b2)), float(1 / solid_angle_)};
}

Vec2 SphericalTriangle::Invert(const Vec3& wi) const {
    const Vec3d w = Normalize(Vec3d(wi));
    // c' is where the great circle through b and w crosses the arc a-c.
    const Vec3d bw = Cross(b_, w);
    if (LengthSquared(bw) == 0) return {0.5f, 0.0f};  // w == b: every u0 maps there
    Vec3d c_prime = Normalize(Cross(bw, Cross(c_, a_)));
    if (Dot(c_prime, a_ + c_) < 0) c_prime = -c_prime;
    const double u0 = UnitSolidAngle(a_, b_, c_prime) / solid_angle_;
    const double one_minus_cos = 1 - Dot(c_prime, b_);
    const double u1 = one_minus_cos > 0 ? (1 - Dot(w, b_)) / one_minus_cos : 0;
    return {float(std::clamp(u0, 0.0, 1.0)), float(std::clamp(u1, 0.0, 1.0))};
}

}  // namespace lf
