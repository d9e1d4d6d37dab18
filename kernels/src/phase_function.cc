#include "lf/kernels/phase_function.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lf {

float HenyeyGreenstein(float cos_theta, float g) {
    // 1 + g^2 - 2 g cos written as (1 - g)^2 + 2 g (1 - cos): no cancellation where g and cos
    // both approach 1 (the forward peak).
    const float denom = (1 - g) * (1 - g) + 2 * g * (1 - cos_theta);
    return (1 - g * g) / (4 * std::numbers::pi_v<float> * denom * std::sqrt(denom));
}

PhaseSample SampleHenyeyGreenstein(const Vec3& d, float g, const Vec2& u) {
    // pbrt-v4's inversion of the cosine's CDF, cos = (1 + g^2 - ((1 - g^2) / (1 + g v))^2) / (2 g)
    // with v = 2 u - 1, multiplied out so that g no longer divides: exact for every g, uniform
    // (cos = v) at g = 0.
    const float v = 2 * u.x - 1, a = 1 + g * v;
    const float numer = v + 0.5f * g * (3 + v * v + g * (2 * v + g * (v * v - 1)));
    const float cos_theta = std::clamp(numer / (a * a), -1.0f, 1.0f);
    const float sin_theta = std::sqrt(std::max(0.0f, 1 - cos_theta * cos_theta));
    const float phi = 2 * std::numbers::pi_v<float> * u.y;
    const Vec3 wi = Frame::FromNormal(d).FromLocal(
        {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta});
    // The density of the direction returned, so that pdf and value agree exactly for MIS.
    return {wi, HenyeyGreenstein(Dot(d, wi), g)};
}

}  // namespace lf
