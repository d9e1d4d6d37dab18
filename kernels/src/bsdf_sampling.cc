#include "lf/kernels/bsdf_sampling.h"

#include <algorithm>
#include <numbers>

namespace lf {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Shirley and Chiu's concentric map: uniform on the unit disk with little distortion.
Vec2 SampleUniformDiskConcentric(const Vec2& u) {
    const float ox = 2 * u.x - 1, oy = 2 * u.y - 1;
    if (ox == 0 && oy == 0) return {0, 0};
    float r, theta;
    if (std::abs(ox) > std::abs(oy)) {
        r = ox;
        theta = kPi / 4 * (oy / ox);
    } else {
        r = oy;
        theta = kPi / 2 - kPi / 4 * (ox / oy);
    }
    return {r * std::cos(theta), r * std::sin(theta)};
}

}  // namespace

Vec3 SampleCosineHemisphere(const Vec2& u) {
    const Vec2 d = SampleUniformDiskConcentric(u);
    return {d.x, d.y, std::sqrt(std::max(0.0f, 1 - d.x * d.x - d.y * d.y))};
}

std::optional<Vec3> Refract(const Vec3& wo, const Vec3& n, float eta) {
    const float cos_i = Dot(wo, n);
    const float sin2_i = std::max(0.0f, 1 - cos_i * cos_i);
    const float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1) return std::nullopt;
    const float cos_t = std::sqrt(1 - sin2_t);
    return -wo / eta + n * (cos_i / eta - cos_t);
}

}  // namespace lf
