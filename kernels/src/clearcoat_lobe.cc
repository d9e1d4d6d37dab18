#include "lf/kernels/clearcoat_lobe.h"

#include <algorithm>

namespace lf {
namespace {

constexpr float kCoatF0 = 0.04f;  // IOR 1.5, as the extension fixes it

float Clamp01(float x) { return x > 0 ? std::min(x, 1.0f) : 0.0f; }  // NaN -> 0

float Schlick(float cos) {
    const float m = std::clamp(1 - cos, 0.0f, 1.0f);
    return kCoatF0 + (1 - kCoatF0) * ((m * m) * (m * m) * m);
}

}  // namespace

ClearcoatLobe::ClearcoatLobe(float factor, float roughness)
    : factor_(Clamp01(factor)),
      distribution_(Material::Distribution::kGgx, Clamp01(roughness) * Clamp01(roughness)),
      albedo_(factor_ > 0 ? &GgxAlbedo::Get() : nullptr),
      albedo_roughness_(GgxAlbedo::At(Clamp01(roughness))) {}

float ClearcoatLobe::Eval(const Vec3& wo, const Vec3& wi) const {
    const Vec3 wm = Normalize(wo + wi);
    return factor_ * Schlick(Dot(wo, wm)) * distribution_.D(wm) *
           distribution_.GOverCosines(wo, wi) / 4;
}

float ClearcoatLobe::Pdf(const Vec3& wo, const Vec3& wi) const {
    const Vec3 wm = Normalize(wo + wi);
    const float cos_om = Dot(wo, wm);
    if (!(cos_om > 0)) return 0;
    return distribution_.PdfWm(wo, wm) / (4 * cos_om);
}

Vec3 ClearcoatLobe::Sample(const Vec3& wo, const Vec2& u) const {
    const Vec3 wm = distribution_.SampleWm(wo, u);
    return wm * (2 * Dot(wo, wm)) - wo;
}

float ClearcoatLobe::Albedo(const Vec3& w) const {
    return factor_ > 0 ? factor_ * albedo_->E(std::min(w.z, 1.0f), albedo_roughness_, kCoatF0) : 0;
}

float ClearcoatLobe::Keep(const Vec3& wo, const Vec3& wi) const {
    return 1 - std::max(Albedo(wo), Albedo(wi));
}

}  // namespace lf
