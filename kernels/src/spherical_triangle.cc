#include "lf/kernels/spherical_triangle.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lf {
namespace {

// Angle between unit vectors, accurate near 0 and pi where acos(dot) is not.
double AngleBetween(const Vec3d& v1, const Vec3d& v2) {
    if (Dot(v1, v2) < 0)
        return std::numbers::pi - 2 * std::asin(std::min(1.0, Length(v1 + v2) / 2));
    return 2 * std::asin(std::min(1.0, Length(v2 - v1) / 2));
}

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

// The component of v orthogonal to the unit vector w, normalised.
Vec3d Orthonormal(const Vec3d& v, const Vec3d& w) { return Normalize(v - w * Dot(v, w)); }

}  // namespace

float TriangleSolidAngle(const Vec3& p, const Vec3& v0, const Vec3& v1, const Vec3& v2) {
    const Vec3d pd(p);
    return float(SolidAngle(Vec3d(v0) - pd, Vec3d(v1) - pd, Vec3d(v2) - pd));
}

SphericalTriangle::SphericalTriangle(const Vec3& p, const Vec3& v0, const Vec3& v1, const Vec3& v2)
    : p_(p), v0_(v0), v1_(v1), v2_(v2) {
    solid_angle_ = SolidAngle(v0_ - p_, v1_ - p_, v2_ - p_);
    if (!(solid_angle_ >= kMinSphericalTriangleSolidAngle &&
          solid_angle_ <= kMaxSphericalTriangleSolidAngle)) {
        return;
    }
    a_ = Normalize(v0_ - p_);
    b_ = Normalize(v1_ - p_);
    c_ = Normalize(v2_ - p_);
    const Vec3d n_ab = Cross(a_, b_), n_ca = Cross(c_, a_);
    if (LengthSquared(n_ab) == 0 || LengthSquared(n_ca) == 0) return;
    // The angle at a between the great circles a-b and a-c.
    alpha_ = AngleBetween(Normalize(n_ab), -Normalize(n_ca));
    samplable_ = std::sin(alpha_) > 0;
}

SphericalTriangleSample SphericalTriangle::Sample(const Vec2& u) const {
    // Arvo's first step: the sub-triangle a b c' of area u0 * A, with c' on the arc a-c, from
    // the spherical law of cosines; q = cos of the arc a-c'.
    const double area = u.x * solid_angle_;
    const double s = std::sin(area - alpha_), t = std::cos(area - alpha_);
    const double cos_alpha = std::cos(alpha_), sin_alpha = std::sin(alpha_);
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
    return {Normalize(Vec3(w)), Vec3(point), float(1 / solid_angle_)};
}

Vec2 SphericalTriangle::Invert(const Vec3& wi) const {
    const Vec3d w = Normalize(Vec3d(wi));
    // c' is where the great circle through b and w crosses the arc a-c.
    const Vec3d bw = Cross(b_, w);
    if (LengthSquared(bw) == 0) return {0.5f, 0.0f};  // w == b: every u0 maps there
    Vec3d c_prime = Normalize(Cross(bw, Cross(c_, a_)));
    if (Dot(c_prime, a_ + c_) < 0) c_prime = -c_prime;
    const double u0 = SolidAngle(a_, b_, c_prime) / solid_angle_;
    const double one_minus_cos = 1 - Dot(c_prime, b_);
    const double u1 = one_minus_cos > 0 ? (1 - Dot(w, b_)) / one_minus_cos : 0;
    return {float(std::clamp(u0, 0.0, 1.0)), float(std::clamp(u1, 0.0, 1.0))};
}

}  // namespace lf
