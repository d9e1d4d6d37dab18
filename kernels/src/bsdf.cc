#include "lf/kernels/bsdf.h"

#include <cmath>
#include <numbers>

#include "lf/kernels/bsdf_sampling.h"
#include "lf/kernels/fresnel.h"

namespace lf {
namespace {

constexpr float kInvPi = std::numbers::inv_pi_v<float>;
constexpr float kMinCos = kBsdfMinCos;

}  // namespace

Bsdf::Bsdf(const Material& material) : Bsdf(material, SurfaceParams::Of(material)) {}

Bsdf::Bsdf(const Material& material, const SurfaceParams& params)
    : type_(material.type),
      conductor_(material.conductor),
      reflectance_(params.base_color),
      eta_(material.eta),
      k_(material.k),
      ior_(material.ior),
      distribution_(material.distribution, material.roughness) {
    if (type_ == Material::Type::kPrincipled) principled_.emplace(material, params);
}

bool Bsdf::IsDelta() const {
    if (principled_) return principled_->IsDelta();
    return type_ == Material::Type::kMirror || type_ == Material::Type::kDielectric;
}

bool Bsdf::HasDeltaLobe() const {
    if (principled_) return principled_->HasDeltaLobe();
    return IsDelta();
}

float Bsdf::RefractionEta(const Vec3& wo, const Vec3& wi) const {
    if (principled_) return principled_->RefractionEta(wo, wi);
    if (type_ != Material::Type::kDielectric || !(wo.z * wi.z < 0)) return 1;
    return wo.z > 0 ? ior_ : 1 / ior_;
}

Rgb Bsdf::GlossyEval(const Vec3& wo, const Vec3& wi) const {
    // Both directions lie above the surface, so wo + wi is never zero and wo.wm > 0.
    const Vec3 wm = Normalize(wo + wi);
    const float cos_om = Dot(wo, wm);
    const Rgb fresnel = conductor_ ? FrComplex(cos_om, eta_, k_) : FrSchlick(reflectance_, cos_om);
    return fresnel * (distribution_.D(wm) * distribution_.GOverCosines(wo, wi) / 4);
}

float Bsdf::GlossyPdf(const Vec3& wo, const Vec3& wi) const {
    const Vec3 wm = Normalize(wo + wi);
    // Jacobian of the reflection wm -> wi.
    return distribution_.PdfWm(wo, wm) / (4 * Dot(wo, wm));
}

Rgb Bsdf::Eval(const Vec3& wo, const Vec3& wi) const {
    if (principled_) return principled_->Eval(wo, wi);
    if (!SameHemisphere(wo, wi)) return {};
    switch (type_) {
        case Material::Type::kLambert:
            return reflectance_ * kInvPi;
        case Material::Type::kGlossy:
            if (std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return {};
            return GlossyEval(ToUpper(wo), ToUpper(wi));
        case Material::Type::kMirror:
        case Material::Type::kDielectric:
        case Material::Type::kPrincipled:  // principled_
        case Material::Type::kInterface:   // scatters nothing: integrators pass through it
            break;
    }
    return {};
}

float Bsdf::Pdf(const Vec3& wo, const Vec3& wi) const {
    if (principled_) return principled_->Pdf(wo, wi);
    if (!SameHemisphere(wo, wi)) return 0;
    switch (type_) {
        case Material::Type::kLambert:
            return std::abs(wi.z) * kInvPi;
        case Material::Type::kGlossy:
            if (std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return 0;
            return GlossyPdf(ToUpper(wo), ToUpper(wi));
        case Material::Type::kMirror:
        case Material::Type::kDielectric:
        case Material::Type::kPrincipled:  // principled_
        case Material::Type::kInterface:   // scatters nothing: integrators pass through it
            break;
    }
    return 0;
}

std::optional<BsdfSample> Bsdf::Sample(const Vec3& wo, float uc, const Vec2& u) const {
    if (principled_) return principled_->Sample(wo, uc, u);
    if (wo.z == 0) return std::nullopt;
    const float side = wo.z > 0 ? 1.0f : -1.0f;
    switch (type_) {
        case Material::Type::kLambert: {
            Vec3 wi = SampleCosineHemisphere(u);
            if (wi.z == 0) return std::nullopt;
            wi.z *= side;
            return BsdfSample{reflectance_ * kInvPi, wi, std::abs(wi.z) * kInvPi, false};
        }
        case Material::Type::kMirror: {
            if (std::abs(wo.z) < kMinCos) return std::nullopt;
            const Vec3 wi(-wo.x, -wo.y, wo.z);
            return BsdfSample{reflectance_ / std::abs(wi.z), wi, 1, true};
        }
        case Material::Type::kGlossy: {
            const Vec3 wo_up = ToUpper(wo);
            if (wo_up.z < kMinCos) return std::nullopt;
            const Vec3 wm = distribution_.SampleWm(wo_up, u);
            const float cos_om = Dot(wo_up, wm);
            // Beckmann samples normals wo cannot see; their mirror direction is below the surface.
            if (cos_om <= 0) return std::nullopt;
            Vec3 wi = wm * (2 * cos_om) - wo_up;
            if (wi.z < kMinCos) return std::nullopt;
            // Eval and Pdf recompute wm from (wo, wi), exactly as MIS weights elsewhere will.
            const Rgb f = GlossyEval(wo_up, wi);
            const float pdf = GlossyPdf(wo_up, wi);
            if (!(pdf > 0)) return std::nullopt;
            wi.z *= side;
            return BsdfSample{f, wi, pdf, false};
        }
        case Material::Type::kDielectric: {
            if (std::abs(wo.z) < kMinCos) return std::nullopt;
            const float reflect = FrDielectric(wo.z, ior_);
            if (uc < reflect) {
                const Vec3 wi(-wo.x, -wo.y, wo.z);
                return BsdfSample{Rgb(reflect / std::abs(wi.z)), wi, reflect, true};
            }
            const float transmit = 1 - reflect;
            const float eta = wo.z > 0 ? ior_ : 1 / ior_;
            const std::optional<Vec3> wi = Refract(wo, Vec3(0, 0, wo.z > 0 ? 1 : -1), eta);
            if (!wi || std::abs(wi->z) < kMinCos || !(transmit > 0)) return std::nullopt;
            // Radiance is compressed into the smaller solid angle of the denser medium.
            const float f = transmit / (std::abs(wi->z) * eta * eta);
            return BsdfSample{Rgb(f), *wi, transmit, true, eta};
        }
        case Material::Type::kPrincipled:  // principled_
        case Material::Type::kInterface:   // scatters nothing: integrators pass through it
            break;
    }
    return std::nullopt;
}

}  // namespace lf
