#include "lf/kernels/bsdf.h"

#include <cmath>
#include <numbers>

#include "lf/kernels/fresnel.h"

namespace lf {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kInvPi = std::numbers::inv_pi_v<float>;

// Lobes whose value divides by a cosine ignore directions this close to the tangent plane: their
// solid angle is negligible, and f there can overflow float.
constexpr float kMinCos = 1e-6f;

bool SameHemisphere(const Vec3& a, const Vec3& b) {
    return (a.z > 0 && b.z > 0) || (a.z < 0 && b.z < 0);
}

// Back-side directions are handled as their mirror images on the front.
Vec3 ToUpper(const Vec3& w) { return {w.x, w.y, std::abs(w.z)}; }

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

Vec3 SampleCosineHemisphere(const Vec2& u) {
    const Vec2 d = SampleUniformDiskConcentric(u);
    return {d.x, d.y, std::sqrt(std::max(0.0f, 1 - d.x * d.x - d.y * d.y))};
}

// Refraction of wo through the z = 0 interface with relative IOR eta (below over above);
// etap receives the IOR ratio across the interface in the direction of travel of the result.
std::optional<Vec3> Refract(const Vec3& wo, float eta, float* etap) {
    float cos_i = wo.z;
    Vec3 n(0, 0, 1);
    if (cos_i < 0) {
        eta = 1 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    const float sin2_i = std::max(0.0f, 1 - cos_i * cos_i);
    const float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1) return std::nullopt;
    const float cos_t = std::sqrt(1 - sin2_t);
    *etap = eta;
    return -wo / eta + n * (cos_i / eta - cos_t);
}

}  // namespace

Bsdf::Bsdf(const Material& material) : Bsdf(material, SurfaceParams::Of(material)) {}

Bsdf::Bsdf(const Material& material, const SurfaceParams& params)
    : type_(material.type),
      conductor_(material.conductor),
      reflectance_(params.base_color),
      eta_(material.eta),
      k_(material.k),
      ior_(material.ior),
      distribution_(material.distribution, material.roughness) {}

bool Bsdf::IsDelta() const {
    return type_ == Material::Type::kMirror || type_ == Material::Type::kDielectric;
}

Rgb Bsdf::GlossyEval(const Vec3& wo, const Vec3& wi) const {
    // Both directions lie above the surface, so wo + wi is never zero and wo.wm > 0.
    const Vec3 wm = Normalize(wo + wi);
    const float cos_om = Dot(wo, wm);
    const Rgb fresnel = conductor_ ? FrComplex(cos_om, eta_, k_) : FrSchlick(reflectance_, cos_om);
    // D G F / (4 cos_o cos_i) with G = 1 / (1 + Lambda_o + Lambda_i) multiplied through, so no
    // grazing direction makes a Lambda infinite.
    const float co = wo.z, ci = wi.z;
    const float denom =
        4 * (co * ci + ci * distribution_.CosLambda(wo) + co * distribution_.CosLambda(wi));
    return fresnel * (distribution_.D(wm) / denom);
}

float Bsdf::GlossyPdf(const Vec3& wo, const Vec3& wi) const {
    const Vec3 wm = Normalize(wo + wi);
    // Jacobian of the reflection wm -> wi.
    return distribution_.PdfWm(wo, wm) / (4 * Dot(wo, wm));
}

Rgb Bsdf::Eval(const Vec3& wo, const Vec3& wi) const {
    if (!SameHemisphere(wo, wi)) return {};
    switch (type_) {
        case Material::Type::kLambert:
            return reflectance_ * kInvPi;
        case Material::Type::kGlossy:
            if (std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return {};
            return GlossyEval(ToUpper(wo), ToUpper(wi));
        case Material::Type::kMirror:
        case Material::Type::kDielectric:
            break;
    }
    return {};
}

float Bsdf::Pdf(const Vec3& wo, const Vec3& wi) const {
    if (!SameHemisphere(wo, wi)) return 0;
    switch (type_) {
        case Material::Type::kLambert:
            return std::abs(wi.z) * kInvPi;
        case Material::Type::kGlossy:
            if (std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return 0;
            return GlossyPdf(ToUpper(wo), ToUpper(wi));
        case Material::Type::kMirror:
        case Material::Type::kDielectric:
            break;
    }
    return 0;
}

std::optional<BsdfSample> Bsdf::Sample(const Vec3& wo, float uc, const Vec2& u) const {
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
            float etap = 1;
            const std::optional<Vec3> wi = Refract(wo, ior_, &etap);
            if (!wi || std::abs(wi->z) < kMinCos || !(transmit > 0)) return std::nullopt;
            // Radiance is compressed into the smaller solid angle of the denser medium.
            const float f = transmit / (std::abs(wi->z) * etap * etap);
            return BsdfSample{Rgb(f), *wi, transmit, true};
        }
    }
    return std::nullopt;
}

}  // namespace lf
