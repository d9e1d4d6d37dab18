#include "lf/kernels/principled_bsdf.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/kernels/bsdf.h"
#include "lf/kernels/bsdf_sampling.h"
#include "lf/kernels/fresnel.h"
#include "lf/kernels/fresnel_mix_albedo.h"

namespace lf {
namespace {

constexpr float kInvPi = std::numbers::inv_pi_v<float>;
constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kMinCos = kBsdfMinCos;

// Lobe picking estimates each lobe's share from wo alone; where the estimate vanishes but the lobe
// does not (Fresnel 1 at the macro normal inside a solid, a black base), a floor keeps every lobe
// that exists sampled.
constexpr float kPickFloor = 0.05f;

// Solids with an IOR this close to one refract by less than float resolves; they are treated as
// thin walls.
constexpr float kMinIorContrast = 1e-3f;

float Clamp01(float x) { return x > 0 ? std::min(x, 1.0f) : 0.0f; }  // NaN -> 0

// The layers' frame for a back-side direction: the whole configuration turned over (w -> -w)
// rather than mirrored (ToUpper), which keeps a tilted coat normal's azimuth; the base's lobes
// are isotropic, so both agree for them.
Vec3 Upright(const Vec3& w) { return w.z < 0 ? -w : w; }

// KHR_materials_specular: ((ior - 1) / (ior + 1))^2 times the specular colour, at most 1.
Rgb DielectricF0(float ior, const Rgb& color) {
    const float f0 = ((ior - 1) / (ior + 1)) * ((ior - 1) / (ior + 1));
    Rgb c;
    for (int i = 0; i < 3; ++i) c[i] = color[i] > 0 ? std::min(f0 * color[i], 1.0f) : 0.0f;
    return c;
}

}  // namespace

PrincipledBsdf::PrincipledBsdf(const Material& material, const SurfaceParams& params)
    : base_(Clamp01(params.base_color.r), Clamp01(params.base_color.g),
            Clamp01(params.base_color.b)),
      metallic_(Clamp01(params.metallic)),
      specular_(Clamp01(params.specular)),
      transmission_(Clamp01(params.transmission)),
      ior_(material.ior),
      f0_color_(DielectricF0(material.ior, params.specular_color)),
      f0_(f0_color_.MaxComponent()),
      refracts_(material.transmission > 0 && material.thickness > 0 &&
                std::abs(material.ior - 1) > kMinIorContrast),
      distribution_(Material::Distribution::kGgx,
                    Clamp01(params.roughness) * Clamp01(params.roughness)),
      // Lambert's limit (no layer, no metal) needs no table: it is not built for it.
      albedo_(specular_ > 0 || metallic_ > 0 ? &GgxAlbedo::Get() : nullptr),
      albedo_roughness_(GgxAlbedo::At(Clamp01(params.roughness))),
      mix_(specular_ > 0 ? &FresnelMixAlbedo::Get() : nullptr),
      smooth_(Clamp01(params.roughness) * Clamp01(params.roughness) <
              MicrofacetDistribution::kMinAlpha),
      diffuse_scale_((1 - metallic_) * (1 - transmission_) * kInvPi),
      coat_(params.clearcoat, params.clearcoat_roughness, params.coat_normal),
      sheen_(params.sheen_color, params.sheen_roughness) {}

Rgb PrincipledBsdf::LayerFresnelColor(float cos_om, bool outside) const {
    if (outside) return FrSchlick(f0_color_, cos_om) * specular_;
    // From inside a solid: Schlick at the cosine the refracted direction would have outside;
    // 1 under total internal reflection.
    const float sin2_t = (1 - cos_om * cos_om) * ior_ * ior_;
    if (sin2_t >= 1) return Rgb(specular_);
    return FrSchlick(f0_color_, std::sqrt(1 - sin2_t)) * specular_;
}

PrincipledBsdf::LobePick PrincipledBsdf::Pick(const Vec3& wo) const {
    const float cos = std::min(std::abs(wo.z), 1.0f);
    const bool outside = Outside(wo);
    // Fresnel as the lobes see it: outside, averaged over the light the microfacets reflect,
    // E(f0) / E(1) (Schlick is linear in f0, so one table serves the layer and the metal); at
    // grazing incidence that is far below Fresnel at the macro normal, which would starve the
    // base and transmission of samples. Inside a solid, at the macro normal with its total
    // internal reflection.
    float layer, metal;
    if (albedo_ && outside) {
        const float e0 = albedo_->E(cos, albedo_roughness_, 0);
        const float e1 = albedo_->E(cos, albedo_roughness_, 1);
        const auto mean_fresnel = [&](float f0) {
            return e1 > 0 ? e0 / e1 + f0 * (1 - e0 / e1) : 1;
        };
        layer = specular_ * mean_fresnel(f0_);
        metal = mean_fresnel(base_.Average());
    } else {
        layer = LayerFresnel(cos, outside);
        metal = FrSchlick(base_, cos).Average();
    }
    const float rest = std::max(1 - layer, kPickFloor);
    const float dielectric = 1 - metallic_;
    LobePick p;
    p.reflect = metallic_ * std::max(metal, kPickFloor) +
                dielectric * std::max(layer, kPickFloor * specular_);
    p.transmit = dielectric * transmission_ * rest;
    if (outside && diffuse_scale_ > 0) {
        p.diffuse = dielectric * (1 - transmission_) * rest * std::max(base_.Average(), kPickFloor);
    }
    const float total = p.reflect + p.transmit + p.diffuse;
    if (!(total > 0)) return {};
    p.reflect /= total;
    p.transmit /= total;
    p.diffuse /= total;
    return p;
}

Rgb PrincipledBsdf::ReflectionFresnel(float cos_om, bool outside) const {
    return FrSchlick(base_, cos_om) * metallic_ +
           LayerFresnelColor(cos_om, outside) * (1 - metallic_);
}

Rgb PrincipledBsdf::ReflectionEval(const Vec3& wo, const Vec3& wi, bool outside) const {
    const Vec3 wm = Normalize(wo + wi);
    // D G / (4 cos_o cos_i), as in the glossy BSDF.
    const float dg = distribution_.D(wm) * distribution_.GOverCosines(wo, wi) / 4;
    return ReflectionFresnel(Dot(wo, wm), outside) * dg;
}

float PrincipledBsdf::ReflectionPdf(const Vec3& wo, const Vec3& wi) const {
    const Vec3 wm = Normalize(wo + wi);
    const float cos_om = Dot(wo, wm);
    if (!(cos_om > 0)) return 0;
    return distribution_.PdfWm(wo, wm) / (4 * cos_om);
}

float PrincipledBsdf::BaseKeep(float mu) const {
    const float layer =
        smooth_ ? LayerFresnel(mu, true) : specular_ * albedo_->E(mu, albedo_roughness_, f0_);
    const float base = mix_->Albedo(mu, specular_, f0_);
    return base > 1 - layer ? (1 - layer) / base : 1;
}

Rgb PrincipledBsdf::DiffuseEval(const Vec3& wo, const Vec3& wi) const {
    if (diffuse_scale_ == 0) return {};
    if (specular_ == 0) return base_ * diffuse_scale_;
    const float cos_oh = Dot(wo, Normalize(wo + wi));
    return base_ *
           (diffuse_scale_ * (1 - LayerFresnel(cos_oh, true)) * BaseKeep(wo.z) * BaseKeep(wi.z));
}

Rgb PrincipledBsdf::DiffuseAlbedo() const {
    if (diffuse_scale_ == 0) return {};
    if (specular_ == 0 && !layered()) return base_ * (diffuse_scale_ * kPi);
    // Directions uniform in cos^2 and azimuth are cosine-distributed, so the integral is pi times
    // the mean of f over the grid; the lobes are isotropic, so wo's azimuth is fixed and wi's
    // spans half the circle.
    constexpr int kN = 16;
    Rgb sum;
    for (int i = 0; i < kN; ++i) {
        const float cos_o = std::sqrt((i + 0.5f) / kN);
        const Vec3 wo(std::sqrt(1 - cos_o * cos_o), 0, cos_o);
        for (int j = 0; j < kN; ++j) {
            const float cos_i = std::sqrt((j + 0.5f) / kN), sin_i = std::sqrt(1 - cos_i * cos_i);
            for (int k = 0; k < kN; ++k) {
                const float phi = kPi * (k + 0.5f) / kN;
                const Vec3 wi(sin_i * std::cos(phi), sin_i * std::sin(phi), cos_i);
                sum += DiffuseEval(wo, wi) * LayerKeep(wo, wi);
            }
        }
    }
    return sum * (kPi / (kN * kN * kN));
}

Rgb PrincipledBsdf::ThinTransmissionEval(const Vec3& wo, const Vec3& wi) const {
    const float weight = (1 - metallic_) * transmission_;
    if (!(weight > 0)) return {};
    const Vec3 wm = Normalize(wo + wi);
    return base_ * (weight * (1 - LayerFresnel(Dot(wo, wm), true)) * distribution_.D(wm) *
                    distribution_.GOverCosines(wo, wi) / 4);
}

std::optional<Vec3> PrincipledBsdf::RefractionNormal(const Vec3& wo, const Vec3& wi) const {
    Vec3 wm = wo + wi * RelativeEta(wo);
    const float length2 = LengthSquared(wm);
    if (!(length2 > 0)) return std::nullopt;
    wm = wm / std::sqrt(length2);
    if (wm.z * wo.z < 0) wm = -wm;
    // Light cannot pass through a microfacet it sees from behind.
    if (Dot(wo, wm) <= 0 || Dot(wi, wm) >= 0) return std::nullopt;
    return wm;
}

Rgb PrincipledBsdf::RefractionEval(const Vec3& wo, const Vec3& wi) const {
    const float weight = (1 - metallic_) * transmission_;
    if (!(weight > 0)) return {};
    const std::optional<Vec3> wm = RefractionNormal(wo, wi);
    if (!wm) return {};
    const float eta = RelativeEta(wo);
    const float cos_om = Dot(wo, *wm), cos_im = Dot(wi, *wm);
    // Schlick at the outside direction's own cosine: the same for the path and its reverse, where
    // Snell's law from the inside would cancel catastrophically near the critical angle.
    const float fresnel = LayerFresnel(wo.z > 0 ? cos_om : -cos_im, true);
    const float half = cos_im + cos_om / eta;
    // Walter et al. (2007) eq. 21; radiance crossing into the medium on wi's side is compressed
    // by 1 / eta^2 (pbrt-v4's TransportMode::Radiance).
    const float value = weight * (1 - fresnel) * distribution_.D(*wm) *
                        distribution_.GOverCosines(wo, wi) * -cos_im * cos_om /
                        (half * half * eta * eta);
    return base_ * std::max(0.0f, value);
}

float PrincipledBsdf::RefractionPdf(const Vec3& wo, const Vec3& wi) const {
    const std::optional<Vec3> wm = RefractionNormal(wo, wi);
    if (!wm) return 0;
    const float eta = RelativeEta(wo);
    const float cos_om = Dot(wo, *wm), cos_im = Dot(wi, *wm);
    const float half = cos_im + cos_om / eta;
    // Jacobian of the refraction wm -> wi.
    return distribution_.PdfWm(ToUpper(wo), ToUpper(*wm)) * -cos_im / (half * half);
}

PrincipledBsdf::LayerPick PrincipledBsdf::PickLayers(const Vec3& wo) const {
    if (!layered() || !Outside(wo)) return {};
    // Each layer in proportion to what it reflects, within bounds that keep every lobe sampled.
    const Vec3 wo_up = Upright(wo);
    LayerPick p;
    if (coat_.active()) p.coat = std::clamp(coat_.Albedo(wo_up), kPickFloor, 0.5f);
    if (sheen_.active())
        p.sheen = std::clamp(sheen_.Albedo(wo_up), kPickFloor, 0.5f) * (1 - p.coat);
    p.rest = 1 - p.coat - p.sheen;
    return p;
}

float PrincipledBsdf::LayerKeep(const Vec3& wo, const Vec3& wi) const {
    float keep = 1;
    if (coat_.active()) keep *= coat_.Keep(wo, wi);
    if (sheen_.active()) keep *= sheen_.Keep(wo, wi);
    return keep;
}

Rgb PrincipledBsdf::Eval(const Vec3& wo, const Vec3& wi) const {
    const Rgb f = BaseEval(wo, wi);
    if (!layered() || std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return f;
    const Vec3 wo_up = Upright(wo), wi_up = Upright(wi);
    if (SameHemisphere(wo, wi)) {
        if (!Outside(wo)) return f;
        Rgb below = f;
        if (sheen_.active()) below = sheen_.Eval(wo_up, wi_up) + below * sheen_.Keep(wo_up, wi_up);
        if (!coat_.active()) return below;
        return Rgb(coat_.Eval(wo_up, wi_up)) + below * coat_.Keep(wo_up, wi_up);
    }
    if (!refracts_) return f * LayerKeep(wo_up, wi_up);
    // Refraction passes the layers once, on the outside.
    const Vec3 outside = wo.z > 0 ? wo : wi;
    return f * LayerKeep(outside, outside);
}

float PrincipledBsdf::Pdf(const Vec3& wo, const Vec3& wi) const {
    const float base = BasePdf(wo, wi);
    const LayerPick pick = PickLayers(wo);
    if (pick.rest == 1 || std::abs(wi.z) < kMinCos) return base;
    float pdf = pick.rest * base;
    if (SameHemisphere(wo, wi)) {
        const Vec3 wo_up = Upright(wo), wi_up = Upright(wi);
        if (pick.coat > 0) pdf += pick.coat * coat_.Pdf(wo_up, wi_up);
        if (pick.sheen > 0) pdf += pick.sheen * SheenLobe::Pdf(wi_up);
    }
    return pdf;
}

Rgb PrincipledBsdf::BaseEval(const Vec3& wo, const Vec3& wi) const {
    if (std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return {};
    const Vec3 wo_up = ToUpper(wo), wi_up = ToUpper(wi);
    if (smooth_) {
        return SameHemisphere(wo, wi) && Outside(wo) ? DiffuseEval(wo_up, wi_up) : Rgb();
    }
    if (SameHemisphere(wo, wi)) {
        const bool outside = Outside(wo);
        Rgb f = ReflectionEval(wo_up, wi_up, outside);
        if (outside) f += DiffuseEval(wo_up, wi_up);
        return f;
    }
    return refracts_ ? RefractionEval(wo, wi) : ThinTransmissionEval(wo_up, wi_up);
}

float PrincipledBsdf::BasePdf(const Vec3& wo, const Vec3& wi) const {
    if (std::abs(wo.z) < kMinCos || std::abs(wi.z) < kMinCos) return 0;
    const LobePick pick = Pick(wo);
    const Vec3 wo_up = ToUpper(wo), wi_up = ToUpper(wi);
    if (smooth_) return SameHemisphere(wo, wi) ? pick.diffuse * wi_up.z * kInvPi : 0;
    if (SameHemisphere(wo, wi)) {
        float pdf = pick.diffuse * wi_up.z * kInvPi;
        if (pick.reflect > 0) pdf += pick.reflect * ReflectionPdf(wo_up, wi_up);
        return pdf;
    }
    if (!(pick.transmit > 0)) return 0;
    return pick.transmit * (refracts_ ? RefractionPdf(wo, wi) : ReflectionPdf(wo_up, wi_up));
}

std::optional<BsdfSample> PrincipledBsdf::Sample(const Vec3& wo, float uc, const Vec2& u) const {
    if (!(std::abs(wo.z) >= kMinCos)) return std::nullopt;
    const LobePick pick = Pick(wo);
    const LayerPick layers = PickLayers(wo);
    if (smooth_ && uc >= layers.coat + layers.sheen) {
        // The base's delta lobes, chosen as Sample chooses below; the layers above pass them
        // as Eval lets them through.
        const float ub = std::min((uc - layers.coat - layers.sheen) / layers.rest, 0x1.fffffep-1f);
        if (ub < pick.reflect || ub >= pick.reflect + pick.diffuse) {
            std::optional<BsdfSample> s = SampleSmooth(wo, ub, pick);
            if (s && layered()) {
                s->pdf *= layers.rest;
                if (SameHemisphere(wo, s->wi)) {
                    if (Outside(wo)) s->f *= LayerKeep(Upright(wo), Upright(s->wi));
                } else if (!refracts_) {
                    s->f *= LayerKeep(Upright(wo), Upright(s->wi));
                } else {
                    const Vec3 outside = wo.z > 0 ? wo : s->wi;
                    s->f *= LayerKeep(outside, outside);
                }
            }
            return s;
        }
    }
    if (uc < layers.coat + layers.sheen) {
        const Vec3 wo_r = Upright(wo);
        const Vec3 wi_r = uc < layers.coat ? coat_.Sample(wo_r, u) : SheenLobe::Sample(u);
        if (wi_r.z < kMinCos) return std::nullopt;
        const Vec3 wi = wo.z > 0 ? wi_r : -wi_r;
        if (uc < layers.coat && coat_.smooth()) {
            return BsdfSample{Rgb(coat_.MirrorReflectance(wo_r) / wi_r.z), wi, layers.coat, true};
        }
        const float pdf = Pdf(wo, wi);
        if (!(pdf > 0)) return std::nullopt;
        return BsdfSample{Eval(wo, wi), wi, pdf, false, 1};
    }
    const Vec3 wo_up = ToUpper(wo);
    const float side = wo.z > 0 ? 1.0f : -1.0f;
    Vec3 wi_up;  // in the frame mirrored so that wo_up.z > 0
    float eta = 1;
    uc = std::min((uc - layers.coat - layers.sheen) / layers.rest, 0x1.fffffep-1f);
    if (uc < pick.reflect + pick.diffuse) {
        if (uc < pick.reflect) {
            const Vec3 wm = distribution_.SampleWm(wo_up, u);
            wi_up = wm * (2 * Dot(wo_up, wm)) - wo_up;
        } else {
            wi_up = SampleCosineHemisphere(u);
        }
        if (wi_up.z < kMinCos) return std::nullopt;
    } else {
        if (!(pick.transmit > 0)) return std::nullopt;
        const Vec3 wm = distribution_.SampleWm(wo_up, u);
        if (refracts_) {
            eta = RelativeEta(wo);
            const std::optional<Vec3> refracted = Refract(wo_up, wm, eta);
            if (!refracted) return std::nullopt;  // total internal reflection at this facet
            wi_up = *refracted;
        } else {
            // A thin wall: the reflection passes through, mirrored to the other side.
            wi_up = wm * (2 * Dot(wo_up, wm)) - wo_up;
            wi_up.z = -wi_up.z;
        }
        if (wi_up.z > -kMinCos) return std::nullopt;
    }
    const Vec3 wi(wi_up.x, wi_up.y, side * wi_up.z);
    // Eval and Pdf recompute the half vector from (wo, wi), exactly as MIS weights elsewhere will.
    const float pdf = Pdf(wo, wi);
    if (!(pdf > 0)) return std::nullopt;
    return BsdfSample{Eval(wo, wi), wi, pdf, false, eta};
}

std::optional<BsdfSample> PrincipledBsdf::SampleSmooth(const Vec3& wo, float uc,
                                                       const LobePick& pick) const {
    const Vec3 wo_up = ToUpper(wo);
    const float side = wo.z > 0 ? 1.0f : -1.0f;
    const bool outside = Outside(wo);
    if (uc < pick.reflect) {
        const Vec3 wi(-wo.x, -wo.y, wo.z);
        const Rgb f = ReflectionFresnel(wo_up.z, outside) / wo_up.z;
        return BsdfSample{f, wi, pick.reflect, true};
    }
    if (!(pick.transmit > 0)) return std::nullopt;
    const float weight = (1 - metallic_) * transmission_;
    if (!refracts_) {
        // A thin wall: straight through.
        const float f = weight * (1 - LayerFresnel(wo_up.z, true)) / wo_up.z;
        return BsdfSample{base_ * f, -wo, pick.transmit, true};
    }
    const float eta = RelativeEta(wo);
    const std::optional<Vec3> refracted = Refract(wo_up, Vec3(0, 0, 1), eta);
    if (!refracted || -refracted->z < kMinCos) return std::nullopt;  // total internal reflection
    const Vec3 wi(refracted->x, refracted->y, side * refracted->z);
    // Fresnel at the outside direction's cosine, as RefractionEval takes it.
    const float fresnel = LayerFresnel(outside ? wo_up.z : -refracted->z, true);
    const float f = weight * (1 - fresnel) / (-refracted->z * eta * eta);
    return BsdfSample{base_ * f, wi, pick.transmit, true, eta};
}

}  // namespace lf
