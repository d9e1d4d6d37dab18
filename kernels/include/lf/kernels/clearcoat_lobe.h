// KHR_materials_clearcoat's layer: a smooth-to-rough GGX dielectric of IOR 1.5 (Schlick, F0 =
// 0.04) with weight `factor`, over whatever lies beneath (lf/kernels/principled_bsdf.h scales
// that by Keep), about its own normal (clearcoatNormalTexture). Directions in the upper
// hemisphere of the shading frame. Below roughness sqrt(MicrofacetDistribution::kMinAlpha) the
// coat is a mirror, a Dirac delta: Eval and Pdf are 0 and Sample reflects exactly, as the
// base's smooth lobes do (as a GGX lobe at the clamped alpha, next-event estimation through it
// gave single samples thousands of times the lights' radiance).
#pragma once

#include "lf/core/vec.h"
#include "lf/kernels/ggx_albedo.h"
#include "lf/kernels/microfacet.h"

namespace lf {

class ClearcoatLobe {
  public:
    // factor in [0, 1]; roughness is glTF's perceptual clearcoatRoughness (alpha = r^2); normal
    // the coat's unit normal in the shading frame (z > 0; anything else is taken as +z).
    ClearcoatLobe(float factor, float roughness, const Vec3& normal = Vec3(0, 0, 1));

    bool active() const { return factor_ > 0; }
    // A mirror: its only lobe is a Dirac delta.
    bool smooth() const { return smooth_; }
    float Eval(const Vec3& wo, const Vec3& wi) const;
    float Pdf(const Vec3& wo, const Vec3& wi) const;
    // Reflects wo about a visible GGX normal (a smooth coat: about its normal); wi may fall below
    // the horizon (the caller drops it).
    Vec3 Sample(const Vec3& wo, const Vec2& u) const;
    // A smooth coat's delta reflection of wo: factor F(cos), what f |cos| carries.
    float MirrorReflectance(const Vec3& wo) const;
    // What the coat reflects of light arriving from w: factor E(cos theta_w) about its normal.
    float Albedo(const Vec3& w) const;
    // The share of light the layer leaves to what lies beneath for the pair (wo, wi): 1 minus the
    // larger of their albedos, symmetric so that the layered BSDF stays reciprocal, and at most
    // 1 - Albedo(wo) so that coat and base never reflect more than arrives.
    float Keep(const Vec3& wo, const Vec3& wi) const;

  private:
    float factor_;
    MicrofacetDistribution distribution_;
    const GgxAlbedo* albedo_;
    GgxAlbedo::Roughness albedo_roughness_;
    bool smooth_;
    Frame frame_;  // the coat's normal is frame_.n
};

}  // namespace lf
