// The principled material: glTF 2.0's metallic-roughness BRDF (its Appendix B) with
// KHR_materials_specular's weight and colour, KHR_materials_ior and
// KHR_materials_transmission/_volume, under KHR_materials_sheen and KHR_materials_clearcoat layers
// (see LayerPick below), in the local shading frame of lf/kernels/bsdf.h (+z the front face's
// normal, the outside).
//
//   f = metallic * conductor + (1 - metallic) * dielectric
//   conductor  = F_schlick(base, wo.wm) D G / (4 cos_o cos_i), GGX with alpha = r^2
//   dielectric = s F D G / (4 cos_o cos_i)                     specular layer, s = `specular`,
//              + t (1 - s F) base BTDF                         F = Schlick with F0 from the IOR
//              + (1 - t) base/pi (1 - s F(wo.h)) k(wo) k(wi)   h = normalize(wo + wi)
//
// Without k that is the specification's fresnel_mix exactly, which is single scattering: it
// loses what the layer scatters more than once (a white base reflects 0.972 at normal incidence
// and roughness 1). But its diffuse weight 1 - F(wo.h) at the half vector can also let base and
// layer reflect more than arrives (white base, IOR 1.5, roughness 0.3: 1.24 at 84 degrees; 1.88
// at grazing incidence on a smooth surface). k(w) = min(1, (1 - s E(w)) / A(w)), E the layer's
// directional albedo (lf/kernels/ggx_albedo.h; Schlick's F for a smooth layer) and A the base
// weight's (lf/kernels/fresnel_mix_albedo.h), is 1 wherever the specification's mix conserves
// energy and scales the base down just enough elsewhere: reciprocal, and the albedo of an opaque
// dielectric never exceeds s E(wo) + (1 - s E(wo)) base.
//
// Below roughness sqrt(MicrofacetDistribution::kMinAlpha) the surface is smooth: reflection and
// transmission are Dirac deltas (BsdfSample::delta); Eval and Pdf hold the diffuse base alone.
// A clear coat that smooth is a delta mirror too (lf/kernels/clearcoat_lobe.h).
//
// The BTDF is tinted by the base colour at every crossing (KHR_materials_transmission), so solid
// glass tints twice, on entry and exit, besides Beer's law inside (lf/kernels/shading.h). With
// `thickness` 0 the surface is a thin wall, and transmission is the specular
// lobe mirrored to the other side (light passes through without bending, blurred by the
// roughness). Above 0 the mesh is the boundary of a solid of relative IOR `ior` and the BTDF is
// Walter et al.'s rough dielectric (2007), F then taken at the cosine on the outside of the
// interface so that it is the same for a path and its reverse, total internal reflection
// included. Seen from inside such a solid only the interface's reflection and transmission
// (and the metal) remain: the diffuse base's share is absorbed there.
#pragma once

#include <optional>

#include "lf/core/rgb.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"
#include "lf/kernels/bsdf_sample.h"
#include "lf/kernels/clearcoat_lobe.h"
#include "lf/kernels/fresnel_mix_albedo.h"
#include "lf/kernels/ggx_albedo.h"
#include "lf/kernels/microfacet.h"
#include "lf/kernels/sheen_lobe.h"

namespace lf {

struct SurfaceParams;

class PrincipledBsdf {
  public:
    // Factors are clamped to their glTF ranges: base colour, metallic, roughness, specular and
    // transmission to [0, 1].
    PrincipledBsdf(const Material& material, const SurfaceParams& params);

    Rgb Eval(const Vec3& wo, const Vec3& wi) const;
    float Pdf(const Vec3& wo, const Vec3& wi) const;
    std::optional<BsdfSample> Sample(const Vec3& wo, float uc, const Vec2& u) const;
    // Every lobe is a Dirac delta: a smooth surface without a diffuse base, under no sheen and
    // no coat or a smooth one.
    bool IsDelta() const {
        return smooth_ && diffuse_scale_ == 0 && !sheen_.active() &&
               (!coat_.active() || coat_.smooth());
    }
    // Some lobe is a Dirac delta: the smooth base's reflection or transmission, or a smooth coat.
    bool HasDeltaLobe() const { return smooth_ || (coat_.active() && coat_.smooth()); }
    // The diffuse base's albedo averaged over both directions, cosine-weighted: (1/pi) times the
    // double integral of f_diffuse cos_o cos_i over the outside hemisphere, under the layers'
    // keep, by a 16^3 midpoint rule. What radiosity takes as the surface's Lambertian
    // reflectance: the energy the path tracer's diffuse lobe carries, without its speculars,
    // transmission, coat and sheen.
    Rgb DiffuseAlbedo() const;
    // Bsdf::RefractionEta: RelativeEta(wo) for a pair across a solid's interface, else 1.
    float RefractionEta(const Vec3& wo, const Vec3& wi) const {
        return refracts_ && wo.z * wi.z < 0 ? RelativeEta(wo) : 1.0f;
    }

  private:
    // The layers over the outside face (KHR_materials_clearcoat over KHR_materials_sheen over
    // the rest): f = coat + Keep_coat (sheen + Keep_sheen base), each Keep symmetric in (wo, wi)
    // (lf/kernels/clearcoat_lobe.h, sheen_lobe.h). Light crossing the surface passes both layers
    // on its outside side and is scaled by their Keep there. Inside a solid there are none.
    // Probabilities of sampling the coat and the sheen for wo; the base lobes get `rest`.
    struct LayerPick {
        float coat = 0, sheen = 0, rest = 1;
    };
    LayerPick PickLayers(const Vec3& wo) const;
    bool layered() const { return coat_.active() || sheen_.active(); }
    // What the layers let through to and from the base for the pair.
    float LayerKeep(const Vec3& wo, const Vec3& wi) const;
    Rgb BaseEval(const Vec3& wo, const Vec3& wi) const;
    float BasePdf(const Vec3& wo, const Vec3& wi) const;

    // Probabilities of sampling the reflection (conductor and specular layer share GGX visible
    // normals), diffuse and transmission lobes for wo; they sum to one, or all are zero.
    struct LobePick {
        float reflect = 0, diffuse = 0, transmit = 0;
    };
    LobePick Pick(const Vec3& wo) const;

    // wo on the outside of the surface: always for thin walls and opaque surfaces.
    bool Outside(const Vec3& wo) const { return !refracts_ || wo.z > 0; }
    // The base's weight k(mu) on one side (see the top).
    float BaseKeep(float mu) const;
    // The specular layer's Fresnel term s F for a microfacet seen at cos_om from one side, per
    // channel (F0 tinted by the specular colour), and its largest channel, which weights what
    // lies beneath (KHR_materials_specular's max_value(F); Schlick is monotone in F0, so it is
    // the Fresnel term of the largest F0).
    Rgb LayerFresnelColor(float cos_om, bool outside) const;
    float LayerFresnel(float cos_om, bool outside) const {
        return LayerFresnelColor(cos_om, outside).MaxComponent();
    }
    // IOR on the far side of the interface over the IOR on wo's side.
    float RelativeEta(const Vec3& wo) const { return wo.z > 0 ? ior_ : 1 / ior_; }

    // The conductor's and the specular layer's Fresnel terms together.
    Rgb ReflectionFresnel(float cos_om, bool outside) const;
    // Lobes, for directions already mirrored to wo.z > 0 (reflection, thin transmission).
    Rgb ReflectionEval(const Vec3& wo, const Vec3& wi, bool outside) const;
    float ReflectionPdf(const Vec3& wo, const Vec3& wi) const;
    Rgb DiffuseEval(const Vec3& wo, const Vec3& wi) const;
    Rgb ThinTransmissionEval(const Vec3& wo, const Vec3& wi) const;
    // Walter et al.'s lobe for wo and wi on opposite sides, in the true frame.
    Rgb RefractionEval(const Vec3& wo, const Vec3& wi) const;
    float RefractionPdf(const Vec3& wo, const Vec3& wi) const;
    // The microfacet normal of a refraction pair, on wo's side; empty for back-facing pairs.
    std::optional<Vec3> RefractionNormal(const Vec3& wo, const Vec3& wi) const;
    // A smooth surface's delta reflection (uc < pick.reflect) or transmission (past the diffuse).
    std::optional<BsdfSample> SampleSmooth(const Vec3& wo, float uc, const LobePick& pick) const;

    Rgb base_;
    float metallic_, specular_, transmission_, ior_;
    Rgb f0_color_;   // min(F0(ior) specular colour, 1)
    float f0_;       // its largest channel
    bool refracts_;  // a solid's interface (thickness > 0) with transmission
    MicrofacetDistribution distribution_;
    const GgxAlbedo* albedo_;
    GgxAlbedo::Roughness albedo_roughness_;
    const FresnelMixAlbedo* mix_;  // for specular > 0
    // alpha below MicrofacetDistribution::kMinAlpha: reflection and transmission are Dirac deltas,
    // as glTF's roughness 0 is a perfect mirror. As a GGX lobe that narrow, a delta light seen
    // through it by next-event estimation gave single samples 1e5 times the light's irradiance.
    bool smooth_;
    float diffuse_scale_;  // (1 - metallic) (1 - transmission) / pi
    ClearcoatLobe coat_;
    SheenLobe sheen_;
};

}  // namespace lf
