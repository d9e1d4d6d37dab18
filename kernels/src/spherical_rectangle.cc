#include "lf/kernels/spherical_rectangle.h"

#include <algorithm>
#include <cmath>

namespace lf {

RectangleFrame::RectangleFrame(const Vec3& corner, const Vec3& ex, const Vec3& ey)
    : corner(corner), ex(ex), ey(ey), ex_length(Length(ex)), ey_length(Length(ey)) {
    if (!(ex_length > 0 && ey_length > 0)) return;
    x = ex / ex_length;
    y = ey / ey_length;
    normal = Cross(x, y);
    center = corner + (ex + ey) * 0.5f;
    half_diagonal = 0.5f * std::sqrt(ex_length * ex_length + ey_length * ey_length);
}

SphericalRectangle::SphericalRectangle(const Vec3& p, const RectangleFrame& r,
                                       float min_solid_angle)
    : p_(p), corner_(r.corner), ex_(r.ex), ey_(r.ey), x_(r.x), y_(r.y) {
    min_solid_angle = std::max(min_solid_angle, kMinSphericalTriangleSolidAngle);
    if (!(r.ex_length > 0 && r.ey_length > 0)) return;
    const Vec3 d = corner_ - p_;
    // The frame's z points to p's side, wherever the rectangle's normal points.
    z0_ = -std::abs(Dot(d, r.normal));
    if (!(z0_ < 0)) return;
    // Far rectangles skip the trigonometry: the solid angle is the integral of |z0| / r^3 over
    // the area, at most A |z0| / r_min^3, with r_min from the bounding sphere about the centre.
    // Half the threshold leaves room for rounding, as for triangles.
    const float r_min = Length(r.center - p_) - r.half_diagonal;
    if (r_min > 0 &&
        r.ex_length * r.ey_length * -z0_ < 0.5f * min_solid_angle * r_min * r_min * r_min) {
        return;
    }
    x0_ = Dot(d, x_);
    y0_ = Dot(d, y_);
    x1_ = x0_ + r.ex_length;
    y1_ = y0_ + r.ey_length;
    b0_ = -y0_ / std::sqrt(z0_ * z0_ + y0_ * y0_);
    b1_ = y1_ / std::sqrt(z0_ * z0_ + y1_ * y1_);
    k_ = AngleSum(x0_);
    solid_angle_ = AngleSum(x1_) - k_;
    samplable_ = solid_angle_ >= min_solid_angle && solid_angle_ <= kMaxSphericalTriangleSolidAngle;
}

float SphericalRectangle::AngleSum(float x) const {
    // The great circle through the edge at x has the unit normal (-z0, 0, x) / |.|: its angles
    // with the other two involve only the z components.
    const float bx = x / std::sqrt(z0_ * z0_ + x * x);
    return std::acos(std::clamp(-b0_ * bx, -1.0f, 1.0f)) +
           std::acos(std::clamp(-b1_ * bx, -1.0f, 1.0f));
}

SphericalRectangleSample SphericalRectangle::Sample(const Vec2& u) const {
    // The edge x = xu that cuts off the solid angle u.x * S: its angle sum is au (Urena et al.,
    // algorithm 1).
    const float au = u.x * solid_angle_ + k_;
    const float fu = (std::cos(au) * b0_ - b1_) / std::sin(au);
    const float cu = std::clamp(std::copysign(1 / std::sqrt(fu * fu + b0_ * b0_), fu), -1.0f, 1.0f);
    float xu = -(cu * z0_) / std::max(std::sqrt(1 - cu * cu), 1e-7f);
    xu = std::isnan(xu) ? x0_ : std::clamp(xu, x0_, x1_);
    // Along that edge, h = cos of the angle to the y axis is uniform between its ends.
    const float d2 = xu * xu + z0_ * z0_;
    const float h0 = y0_ / std::sqrt(d2 + y0_ * y0_), h1 = y1_ / std::sqrt(d2 + y1_ * y1_);
    const float hv = h0 + u.y * (h1 - h0), hv2 = hv * hv;
    const float yv =
        hv2 < 1 ? std::clamp(hv * std::sqrt(d2 / (1 - hv2)), y0_, y1_) : (hv > 0 ? y1_ : y0_);

    const float s = std::clamp((xu - x0_) / (x1_ - x0_), 0.0f, 1.0f);
    const float t = std::clamp((yv - y0_) / (y1_ - y0_), 0.0f, 1.0f);
    const Vec3 point = corner_ + ex_ * s + ey_ * t;
    return {Normalize(point - p_), point, Vec2(s, t), 1 / solid_angle_};
}

Vec2 SphericalRectangle::Invert(const Vec3& point) const {
    const Vec3 q = point - p_;
    const float xu = std::clamp(Dot(q, x_), x0_, x1_), yv = std::clamp(Dot(q, y_), y0_, y1_);
    const float u0 = (AngleSum(xu) - k_) / solid_angle_;
    const float d2 = xu * xu + z0_ * z0_;
    const float h0 = y0_ / std::sqrt(d2 + y0_ * y0_), h1 = y1_ / std::sqrt(d2 + y1_ * y1_);
    const float hv = yv / std::sqrt(d2 + yv * yv);
    const float u1 = h1 > h0 ? (hv - h0) / (h1 - h0) : 0.5f;
    return {std::clamp(u0, 0.0f, 1.0f), std::clamp(u1, 0.0f, 1.0f)};
}

}  // namespace lf
