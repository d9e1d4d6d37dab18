#include "lf/core/disk_sampling.h"

#include <cmath>
#include <numbers>

namespace lf {

Vec2 SampleUniformDiskConcentric(const Vec2& u) {
    constexpr float kPi = std::numbers::pi_v<float>;
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

}  // namespace lf
