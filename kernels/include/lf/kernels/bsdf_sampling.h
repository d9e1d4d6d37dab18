// Direction sampling and geometry shared by the BSDFs, in a local frame whose +z is the normal.
#pragma once

#include <cmath>
#include <optional>

#include "lf/core/vec.h"

namespace lf {

// Lobes whose value divides by a cosine ignore directions this close to the tangent plane: their
// solid angle is negligible, and f there can overflow float.
constexpr float kBsdfMinCos = 1e-6f;

// Cosine-weighted directions on the upper hemisphere (Malley's method over Shirley and Chiu's
// concentric disk map).
Vec3 SampleCosineHemisphere(const Vec2& u);

// Back-side directions are handled as their mirror images on the front.
inline Vec3 ToUpper(const Vec3& w) { return {w.x, w.y, std::abs(w.z)}; }

inline bool SameHemisphere(const Vec3& a, const Vec3& b) {
    return (a.z > 0 && b.z > 0) || (a.z < 0 && b.z < 0);
}

// Refraction of wo through an interface with unit normal n on wo's side (Dot(wo, n) > 0); eta is
// the IOR on the far side over the IOR on wo's side. Empty under total internal reflection.
std::optional<Vec3> Refract(const Vec3& wo, const Vec3& n, float eta);

}  // namespace lf
