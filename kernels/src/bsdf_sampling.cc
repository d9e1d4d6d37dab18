#include "lf/kernels/bsdf_sampling.h"

#include <algorithm>

#include "lf/core/disk_sampling.h"

namespace lf {
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
