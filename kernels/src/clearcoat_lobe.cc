#include "lf/kernels/clearcoat_lobe.h"

#include <algorithm>
#include <cmath>

namespace lf {
namespace {

constexpr float kCoatF0 = 0.04f;  // IOR 1.5, as the extension fixes it

float Clamp01(float x) { return x > 0 ? std::min(x, 1.0f) : 0.0f; }  // NaN -> 0

float Schlick(float cos) {
    const float m = std::clamp(1 - cos, 0.0f, 1.0f);
    return kCoatF0 + (1 - kCoatF0) * ((m * m) * (m * m) * m);
}

Vec3 CoatNormal(const Vec3& n) {
    const float length2 = LengthSquared(n);
    if (!(n.z > 0) || !(length2 > 0) || !std::isfinite(length2)) return Vec3(0, 0, 1);
    return n / std::sqrt(length2);
}

}  // namespace

ClearcoatLobe::ClearcoatLobe(float factor, float roughness, const Vec3& normal)
    : factor_(Clamp01(factor)),
      distribution_(Material::Distribution::kGgx, Clamp01(roughness) * Clamp01(roughness)),
      albedo_(factor_ > 0 ? &GgxAlbedo::Get() : nullptr),
      albedo_roughness_(GgxAlbedo::At(Clamp01(roughness))),
      smooth_(Clamp01(roughness) * Clamp01(roughness) < MicrofacetDistribution::kMinAlpha),
      frame_(Frame::FromNormal(CoatNormal(normal))) {}

float ClearcoatLobe::Eval(const Vec3& wo, const Vec3& wi) const {
    if (smooth_) return 0;
    const Vec3 o = frame_.ToLocal(wo), i = frame_.ToLocal(wi);
    if (!(o.z > 0) || !(i.z > 0)) return 0;
    const Vec3 wm = Normalize(o + i);
    return factor_ * Schlick(Dot(o, wm)) * distribution_.D(wm) * distribution_.GOverCosines(o, i) /
           4;
}

float ClearcoatLobe::Pdf(const Vec3& wo, const Vec3& wi) const {
    if (smooth_) return 0;
    const Vec3 o = frame_.ToLocal(wo), i = frame_.ToLocal(wi);
    if (!(o.z > 0) || !(i.z > 0)) return 0;
    const Vec3 wm = Normalize(o + i);
    const float cos_om = Dot(o, wm);
    if (!(cos_om > 0)) return 0;
    return distribution_.PdfWm(o, wm) / (4 * cos_om);
}

Vec3 ClearcoatLobe::Sample(const Vec3& wo, const Vec2& u) const {
    const Vec3 o = frame_.ToLocal(wo);
    if (!(o.z > 0)) return Vec3(0, 0, -1);  // wo below the coat: nothing to reflect
    const Vec3 wm = smooth_ ? Vec3(0, 0, 1) : distribution_.SampleWm(o, u);
    return frame_.FromLocal(wm * (2 * Dot(o, wm)) - o);
}

float ClearcoatLobe::MirrorReflectance(const Vec3& wo) const {
    const float cos = Dot(wo, frame_.n);
    return cos > 0 ? factor_ * Schlick(cos) : 0;
}

float ClearcoatLobe::Albedo(const Vec3& w) const {
    if (!(factor_ > 0)) return 0;
    const float cos = std::min(Dot(w, frame_.n), 1.0f);
    if (!(cos > 0)) return 0;
    return smooth_ ? factor_ * Schlick(cos) : factor_ * albedo_->E(cos, albedo_roughness_, kCoatF0);
}

float ClearcoatLobe::Keep(const Vec3& wo, const Vec3& wi) const {
    return 1 - std::max(Albedo(wo), Albedo(wi));
}

}  // namespace lf
