#include "lf/kernels/light_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace lf {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

float SafeSqrt(float x) { return std::sqrt(std::max(0.0f, x)); }

// cos(max(0, theta_a - theta_b)) and sin(max(0, theta_a - theta_b)) from the sines and cosines
// of the two angles in [0, pi].
float CosSubClamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    if (cos_a > cos_b) return 1;
    return cos_a * cos_b + sin_a * sin_b;
}
float SinSubClamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    if (cos_a > cos_b) return 0;
    return sin_a * cos_b - cos_a * sin_b;
}

float Angle(float cos_theta) { return std::acos(std::clamp(cos_theta, -1.0f, 1.0f)); }

}  // namespace

float LightBounds::Importance(const Vec3& p, const Vec3& n) const {
    const Vec3 center = (lower + upper) * 0.5f;
    const Vec3 from_light = p - center;
    const float dist2 = LengthSquared(from_light);
    const float radius2 = LengthSquared(upper - lower) * 0.25f;
    // Inside the box's bounding sphere the distance is unknown: the sphere's radius stands in.
    const float d2 = std::max(dist2, radius2);
    const Vec3 wi = dist2 > 0 ? from_light / std::sqrt(dist2) : Vec3(0, 0, 1);

    // theta_b: half the angle the box's bounding sphere subtends at p (pi from inside it).
    const float cos_b = dist2 <= radius2 ? -1.0f : SafeSqrt(1 - radius2 / dist2);
    const float sin_b = SafeSqrt(1 - cos_b * cos_b);

    // The smallest angle between an emitting normal and the direction to p: theta_w - theta_o -
    // theta_b, clamped at zero.
    float cos_w = Dot(axis, wi);
    if (two_sided) cos_w = std::abs(cos_w);
    const float sin_w = SafeSqrt(1 - cos_w * cos_w);
    const float sin_o = SafeSqrt(1 - cos_theta_o * cos_theta_o);
    const float cos_x = CosSubClamped(sin_w, cos_w, sin_o, cos_theta_o);
    const float sin_x = SinSubClamped(sin_w, cos_w, sin_o, cos_theta_o);
    const float cos_p = CosSubClamped(sin_x, cos_x, sin_b, cos_b);
    // Strict: a hard-edged spot (theta_e = 0) still lights its own cone.
    if (cos_p < cos_theta_e) return 0;

    float importance = phi * cos_p / d2;
    if (n.x != 0 || n.y != 0 || n.z != 0) {
        // The receiver's cosine, at the most favourable angle over the box.
        const float cos_i = AbsDot(wi, n);
        const float sin_i = SafeSqrt(1 - cos_i * cos_i);
        importance *= CosSubClamped(sin_i, cos_i, sin_b, cos_b);
    }
    return std::clamp(importance, 0.0f, std::numeric_limits<float>::max());
}

LightBounds Union(const LightBounds& a, const LightBounds& b) {
    if (a.phi == 0) return b;
    if (b.phi == 0) return a;
    LightBounds u;
    u.lower = Min(a.lower, b.lower);
    u.upper = Max(a.upper, b.upper);
    u.phi = a.phi + b.phi;
    u.cos_theta_e = std::min(a.cos_theta_e, b.cos_theta_e);
    u.two_sided = a.two_sided || b.two_sided;

    // The smallest cone about both cones (pbrt-v4's DirectionCone Union): one may hold the
    // other; else the new axis lies on the great circle between the two.
    const float theta_a = Angle(a.cos_theta_o), theta_b = Angle(b.cos_theta_o);
    const float theta_d = Angle(Dot(a.axis, b.axis));
    if (std::min(theta_d + theta_b, kPi) <= theta_a) {
        u.axis = a.axis;
        u.cos_theta_o = a.cos_theta_o;
        return u;
    }
    if (std::min(theta_d + theta_a, kPi) <= theta_b) {
        u.axis = b.axis;
        u.cos_theta_o = b.cos_theta_o;
        return u;
    }
    const float theta_o = (theta_a + theta_d + theta_b) / 2;
    const Vec3 normal = Cross(a.axis, b.axis);
    if (theta_o >= kPi || LengthSquared(normal) == 0) {
        u.axis = a.axis;
        u.cos_theta_o = -1;
        return u;
    }
    // Rotate a's axis towards b's by theta_o - theta_a.
    const float theta_r = theta_o - theta_a;
    const Vec3 towards_b = Normalize(Cross(normal, a.axis));
    u.axis = Normalize(a.axis * std::cos(theta_r) + towards_b * std::sin(theta_r));
    u.cos_theta_o = std::cos(theta_o);
    return u;
}

LightBounds TriangleLightBounds(const Vec3& v0, const Vec3& v1, const Vec3& v2, float radiance,
                                bool two_sided) {
    const Vec3 cross = Cross(v1 - v0, v2 - v0);
    const float length = Length(cross);
    LightBounds b;
    b.lower = Min(v0, Min(v1, v2));
    b.upper = Max(v0, Max(v1, v2));
    b.phi = kPi * radiance * 0.5f * length * (two_sided ? 2 : 1);
    b.axis = length > 0 ? cross / length : Vec3(0, 0, 1);
    b.cos_theta_o = 1;
    b.cos_theta_e = 0;
    b.two_sided = two_sided;
    return b;
}

LightBounds SphereLightBounds(const Vec3& center, float radius, float radiance) {
    LightBounds b;
    b.lower = center - Vec3(radius, radius, radius);
    b.upper = center + Vec3(radius, radius, radius);
    b.phi = kPi * radiance * 4 * kPi * radius * radius;
    b.cos_theta_o = -1;
    b.cos_theta_e = 0;
    return b;
}

LightBounds PointLightBounds(const Vec3& position, float intensity) {
    LightBounds b;
    b.lower = b.upper = position;
    b.phi = 4 * kPi * intensity;
    b.cos_theta_o = -1;
    b.cos_theta_e = 0;
    return b;
}

LightBounds SpotLightBounds(const Vec3& position, const Vec3& direction, float intensity,
                            float cos_inner, float cos_outer) {
    LightBounds b = PointLightBounds(position, intensity);
    b.axis = direction;
    b.cos_theta_o = cos_inner;
    b.cos_theta_e = std::cos(std::max(0.0f, Angle(cos_outer) - Angle(cos_inner)));
    return b;
}

}  // namespace lf
