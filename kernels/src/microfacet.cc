#include "lf/kernels/microfacet.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lf {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

}  // namespace

MicrofacetDistribution::MicrofacetDistribution(Material::Distribution type, float alpha)
    // Argument order makes a NaN alpha fall back to the minimum.
    : type_(type), alpha_(std::max(kMinAlpha, alpha)) {}

float MicrofacetDistribution::D(const Vec3& wm) const {
    const float sin2 = wm.x * wm.x + wm.y * wm.y;
    const float cos2 = wm.z * wm.z;
    const float a2 = alpha_ * alpha_;
    if (type_ == Material::Distribution::kGgx) {
        // cos^4 (alpha^2 + tan^2)^2 rewritten for unit wm: no tan, so no overflow near the
        // horizon and no cancellation near the pole.
        const float d = sin2 + a2 * cos2;
        return a2 / (kPi * d * d);
    }
    if (cos2 == 0) return 0;
    // Double: cos^4 underflows float long before the exponential reaches zero.
    const double c2 = cos2;
    return float(std::exp(-double(sin2) / (double(a2) * c2)) / (std::numbers::pi * a2 * c2 * c2));
}

float MicrofacetDistribution::CosLambda(const Vec3& w) const {
    const float sin2 = w.x * w.x + w.y * w.y;
    if (sin2 == 0) return 0;
    const float cos = std::abs(w.z);
    if (type_ == Material::Distribution::kGgx) {
        // |cos| (sqrt(1 + alpha^2 tan^2) - 1) / 2 with the difference rationalised.
        const float a2s2 = alpha_ * alpha_ * sin2;
        return a2s2 / (2 * (std::sqrt(cos * cos + a2s2) + cos));
    }
    // Lambda(a) = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2 with a = cot / alpha; multiplying by
    // |cos| cancels the 1/a pole.
    const double alpha_sin = double(alpha_) * std::sqrt(double(sin2));
    const double a = cos / alpha_sin;
    const double value =
        (alpha_sin * std::exp(-a * a) * std::numbers::inv_sqrtpi - cos * std::erfc(a)) / 2;
    return float(std::max(0.0, value));
}

float MicrofacetDistribution::G1(const Vec3& w) const {
    const float cos = std::abs(w.z);
    const float denom = cos + CosLambda(w);
    return denom > 0 ? cos / denom : 0;
}

float MicrofacetDistribution::G(const Vec3& wo, const Vec3& wi) const {
    const float co = std::abs(wo.z), ci = std::abs(wi.z);
    const float denom = co * ci + ci * CosLambda(wo) + co * CosLambda(wi);
    return denom > 0 ? co * ci / denom : 0;
}

float MicrofacetDistribution::GOverCosines(const Vec3& wo, const Vec3& wi) const {
    const float co = std::abs(wo.z), ci = std::abs(wi.z);
    return 1 / (co * ci + ci * CosLambda(wo) + co * CosLambda(wi));
}

Vec3 MicrofacetDistribution::SampleWm(const Vec3& wo, const Vec2& u) const {
    const float phi = 2 * kPi * u.y;
    if (type_ == Material::Distribution::kBeckmann) {
        // u.x < 1, so the logarithm is finite.
        const float tan2 = -alpha_ * alpha_ * std::log1p(-u.x);
        const float cos = 1 / std::sqrt(1 + tan2);
        const float sin = std::sqrt(tan2) * cos;
        return {sin * std::cos(phi), sin * std::sin(phi), cos};
    }
    // Stretch wo so the distribution becomes the unit hemisphere, sample the projected area of
    // that hemisphere seen from wo, and unstretch (pbrt-v4 TrowbridgeReitzDistribution).
    const Vec3 wh = Normalize(Vec3(alpha_ * wo.x, alpha_ * wo.y, wo.z));
    const Vec3 t1 = wh.z < 0.99999f ? Normalize(Cross(Vec3(0, 0, 1), wh)) : Vec3(1, 0, 0);
    const Vec3 t2 = Cross(wh, t1);
    const float r = std::sqrt(u.x);
    const float px = r * std::cos(phi);
    float py = r * std::sin(phi);
    const float h = std::sqrt(std::max(0.0f, 1 - px * px));
    const float s = (1 + wh.z) / 2;
    py = (1 - s) * h + s * py;
    const float pz = std::sqrt(std::max(0.0f, 1 - px * px - py * py));
    const Vec3 nh = t1 * px + t2 * py + wh * pz;
    return Normalize(Vec3(alpha_ * nh.x, alpha_ * nh.y, std::max(1e-6f, nh.z)));
}

float MicrofacetDistribution::PdfWm(const Vec3& wo, const Vec3& wm) const {
    if (wm.z <= 0) return 0;
    if (type_ == Material::Distribution::kBeckmann) return D(wm) * wm.z;
    // D_wo(wm) = G1(wo) max(0, wo.wm) D(wm) / cos(theta_o).
    const float cos_om = Dot(wo, wm);
    if (cos_om <= 0) return 0;
    return D(wm) * cos_om / (std::abs(wo.z) + CosLambda(wo));
}

}  // namespace lf
