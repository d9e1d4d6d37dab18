#include "lf/kernels/sphere_cone_sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// From p on or inside the sphere there is no cone: every direction sees it. "On" includes the
// rounding of a point on the sphere itself (a hit on an emissive sphere seen from inside lies
// half the time just outside it in float): seen from just outside, the cone would be a
// hemisphere whose every ray meets the sphere at p itself, so next-event estimation from the
// inside of a spherical emitter would find nothing while its Pdf says otherwise. Area sampling
// stays exact for points that truly lie within the tolerance outside.
constexpr double kOnSphereTolerance = 1e-5;  // relative, on the squared distance
bool Inside(const Vec3& p, const Vec3& center, float radius) {
    return LengthSquared(Vec3d(p) - Vec3d(center)) <=
           double(radius) * radius * (1 + kOnSphereTolerance);
}

// 1 - cos(theta_max) of the cone sin^2(theta_max) = sin2, written so that it keeps its digits
// for a distant sphere, where cos(theta_max) rounds to 1.
double OneMinusCosThetaMax(double sin2) { return sin2 / (1 + std::sqrt(std::max(0.0, 1 - sin2))); }

double SinSquaredThetaMax(const Vec3& p, const Vec3& center, float radius) {
    return double(radius) * radius / LengthSquared(Vec3d(p) - Vec3d(center));
}

// The uniform area density 1 / (4 pi r^2) of `point` (outward unit `normal`) per solid angle at
// p; 0 where it has no finite value.
float AreaPdfPerSolidAngle(const Vec3& p, const Vec3& point, const Vec3& normal, float radius) {
    const Vec3d d = Vec3d(point) - Vec3d(p);
    const double dist2 = LengthSquared(d);
    const double cos_light = std::abs(Dot(Vec3d(normal), d)) / std::sqrt(dist2);
    if (!(dist2 > 0) || !(cos_light > 0)) return 0;
    return float(dist2 / (cos_light * 4 * kPi * double(radius) * radius));
}

}  // namespace

std::optional<SphereConeSample> SampleSphereCone(const Vec3& p, const Vec3& center, float radius,
                                                 const Vec2& u) {
    if (!(radius > 0)) return std::nullopt;
    SphereConeSample s;
    if (Inside(p, center, radius)) {
        const double z = 1 - 2 * double(u.x), phi = 2 * kPi * u.y;
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        s.normal = Vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
        s.point = center + s.normal * radius;
        s.pdf = AreaPdfPerSolidAngle(p, s.point, s.normal, radius);
        if (s.pdf == 0) return std::nullopt;
    } else {
        // theta, from the axis p -> centre, with 1 - cos(theta) uniform in [0, 1 - cos max]:
        // kept as one_minus_cos so that narrow cones do not round to a line.
        const double sin2_max = SinSquaredThetaMax(p, center, radius);
        const double one_minus_cos_max = OneMinusCosThetaMax(sin2_max);
        const double one_minus_cos = u.x * one_minus_cos_max;
        const double sin2 = one_minus_cos * (2 - one_minus_cos);
        const double cos_theta = 1 - one_minus_cos;
        // alpha, at the centre between the direction to p and the sampled point, where the ray
        // at theta first meets the sphere: cos(alpha) = (d - t cos(theta)) / r with
        // t = d cos(theta) - sqrt(r^2 - d^2 sin^2(theta)).
        const double cos_alpha =
            sin2 / std::sqrt(sin2_max) + cos_theta * std::sqrt(std::max(0.0, 1 - sin2 / sin2_max));
        const double sin_alpha = std::sqrt(std::max(0.0, (1 - cos_alpha) * (1 + cos_alpha)));
        const double phi = 2 * kPi * u.y;
        const Frame frame = Frame::FromNormal(Normalize(p - center));
        s.normal = Normalize(frame.FromLocal(Vec3(
            float(sin_alpha * std::cos(phi)), float(sin_alpha * std::sin(phi)), float(cos_alpha))));
        s.point = center + s.normal * radius;
        s.pdf = float(1 / (2 * kPi * one_minus_cos_max));
    }
    const Vec3 d = s.point - p;
    const float length = Length(d);
    if (!(length > 0)) return std::nullopt;
    s.wi = d / length;
    return s;
}

float SphereConePdf(const Vec3& p, const Vec3& center, float radius, const Vec3& point) {
    if (!(radius > 0)) return 0;
    if (Inside(p, center, radius)) {
        return AreaPdfPerSolidAngle(p, point, Normalize(point - center), radius);
    }
    return float(1 / (2 * kPi * OneMinusCosThetaMax(SinSquaredThetaMax(p, center, radius))));
}

}  // namespace lf
