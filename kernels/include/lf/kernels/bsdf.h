// BSDFs of the five material types (the principled one in lf/kernels/principled_bsdf.h),
// evaluated and sampled in a local shading frame whose +z is the front face's normal.
// Reflection happens on both faces (lambert, mirror, glossy, principled): a pair of directions on
// the back side is treated as its mirror image on the front. For dielectrics (and principled
// solids) +z is the outside. Values are f(wo, wi) without the cosine; Pdf is per solid angle.
#pragma once

#include <optional>

#include "lf/core/rgb.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"
#include "lf/kernels/bsdf_sample.h"
#include "lf/kernels/microfacet.h"
#include "lf/kernels/principled_bsdf.h"

namespace lf {

// The parameters that vary across a surface, at one point: the material's factors times its
// textures there (lf/kernels/shading.h). Everything else of the BSDF comes from the Material.
struct SurfaceParams {
    Rgb base_color;  // lambert albedo, principled base colour
    float metallic = 0;
    float roughness = 0;  // principled: perceptual roughness r
    float specular = 1;   // principled: the specular layer's weight and F0 tint
    Rgb specular_color{1.0f};
    float clearcoat = 0, clearcoat_roughness = 0;
    // The coat's own normal (clearcoatNormalTexture) in the shading frame of lf/core/vec.h's
    // Frame::FromNormal(ns), which every estimator builds; +z is the shading normal itself.
    Vec3 coat_normal{0, 0, 1};
    Rgb sheen_color;
    float sheen_roughness = 0;
    float transmission = 0;  // principled; whether the material is a solid stays the Material's

    static SurfaceParams Of(const Material& m) {
        SurfaceParams p;
        p.base_color = m.reflectance;
        p.metallic = m.metallic;
        p.roughness = m.roughness;
        p.specular = m.specular;
        p.specular_color = m.specular_color;
        p.clearcoat = m.clearcoat;
        p.clearcoat_roughness = m.clearcoat_roughness;
        p.sheen_color = m.sheen_color;
        p.sheen_roughness = m.sheen_roughness;
        p.transmission = m.transmission;
        return p;
    }
};

class Bsdf {
  public:
    // The material's own constant parameters.
    explicit Bsdf(const Material& material);
    Bsdf(const Material& material, const SurfaceParams& params);

    Rgb Eval(const Vec3& wo, const Vec3& wi) const;
    float Pdf(const Vec3& wo, const Vec3& wi) const;
    // uc picks a lobe (Fresnel reflect vs refract), u the direction.
    std::optional<BsdfSample> Sample(const Vec3& wo, float uc, const Vec2& u) const;

    // True when every lobe is a Dirac delta: light sampling is useless there.
    bool IsDelta() const;
    // True when some lobe is a Dirac delta (Sample may return BsdfSample::delta): a smooth
    // principled surface over a diffuse base has both kinds, and estimators that gather light
    // at non-delta vertices (Whitted, photon mapping) must still follow its delta lobes.
    bool HasDeltaLobe() const;

    // For a pair that crosses a refracting interface (a dielectric, a principled solid), the IOR
    // on wi's side over the IOR on wo's side, as BsdfSample::eta reports it; else 1. Eval
    // divides such pairs by its square (radiance); light paths, which carry importance's adjoint,
    // multiply it back (pbrt-v4's TransportMode::Importance, lf/kernels/light_tracer.h).
    float RefractionEta(const Vec3& wo, const Vec3& wi) const;

  private:
    // The glossy lobe for wo and wi both in the upper hemisphere.
    Rgb GlossyEval(const Vec3& wo, const Vec3& wi) const;
    float GlossyPdf(const Vec3& wo, const Vec3& wi) const;

    // Copies rather than a Material pointer: a Bsdf built from a temporary stays valid, and the
    // name string is never touched.
    Material::Type type_;
    bool conductor_;
    Rgb reflectance_, eta_, k_;
    float ior_;
    MicrofacetDistribution distribution_;
    std::optional<PrincipledBsdf> principled_;  // kPrincipled only
};

}  // namespace lf
