#include "lf/kernels/fresnel.h"

#include <algorithm>
#include <cmath>

namespace lf {

float FrDielectric(float cos_theta_i, float eta) {
    cos_theta_i = std::clamp(cos_theta_i, -1.0f, 1.0f);
    if (cos_theta_i < 0) {
        eta = 1 / eta;
        cos_theta_i = -cos_theta_i;
    }
    const float sin2_theta_i = 1 - cos_theta_i * cos_theta_i;
    const float sin2_theta_t = sin2_theta_i / (eta * eta);
    if (sin2_theta_t >= 1) return 1;
    const float cos_theta_t = std::sqrt(std::max(0.0f, 1 - sin2_theta_t));
    const float r_parl = (eta * cos_theta_i - cos_theta_t) / (eta * cos_theta_i + cos_theta_t);
    const float r_perp = (cos_theta_i - eta * cos_theta_t) / (cos_theta_i + eta * cos_theta_t);
    return (r_parl * r_parl + r_perp * r_perp) / 2;
}

float FrComplex(float cos_theta_i, std::complex<float> eta) {
    using Complex = std::complex<float>;
    cos_theta_i = std::clamp(cos_theta_i, 0.0f, 1.0f);
    const float sin2_theta_i = 1 - cos_theta_i * cos_theta_i;
    const Complex sin2_theta_t = sin2_theta_i / (eta * eta);
    const Complex cos_theta_t = std::sqrt(1.0f - sin2_theta_t);
    const Complex r_parl = (eta * cos_theta_i - cos_theta_t) / (eta * cos_theta_i + cos_theta_t);
    const Complex r_perp = (cos_theta_i - eta * cos_theta_t) / (cos_theta_i + eta * cos_theta_t);
    return (std::norm(r_parl) + std::norm(r_perp)) / 2;
}

Rgb FrComplex(float cos_theta_i, const Rgb& eta, const Rgb& k) {
    Rgb result;
    for (int c = 0; c < 3; ++c) result[c] = FrComplex(cos_theta_i, {eta[c], k[c]});
    return result;
}

Rgb FrSchlick(const Rgb& f0, float cos_theta_i) {
    const float m = std::clamp(1 - cos_theta_i, 0.0f, 1.0f);
    const float m5 = (m * m) * (m * m) * m;
    return f0 + (Rgb(1.0f) - f0) * m5;
}

}  // namespace lf
