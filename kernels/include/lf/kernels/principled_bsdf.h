// The principled material: glTF 2.0's metallic-roughness BRDF (its Appendix B) with
// KHR_materials_specular's weight, KHR_materials_ior and KHR_materials_transmission/_volume,
// under KHR_materials_sheen and KHR_materials_clearcoat layers (see LayerPick below),
// in the local shading frame of lf/kernels/bsdf.h (+z the front face's normal, the outside).
//
//   f = metallic * conductor + (1 - metallic) * dielectric
//   conductor  = F_schlick(base, wo.wm) D G / (4 cos_o cos_i), GGX with alpha = r^2
//   dielectric = s F D G / (4 cos_o cos_i)                     specular layer, s = `specular`,
//              + t (1 - s F) base BTDF                         F = Schlick with F0 from the IOR
//              + (1 - t) base/pi (1 - s E(wo)) (1 - s E(wi)) / (1 - s E_avg)
//
// The last line is where this departs from the specification: its diffuse weight 1 - F(wo.wm)
// taken at the half vector lets base and layer reflect more than arrives (white base, IOR 1.5:
// albedo 1.15 at 73 degrees, 1.88 at grazing incidence on a smooth surface). Scaling the base by 1
// - E, the layer's directional albedo (lf/kernels/ggx_albedo.h), on both sides and renormalising by
// the cosine-weighted average (Kelemen and Szirmay-Kalos 2001; Kulla and Conty 2017) keeps the BRDF
// reciprocal and makes the albedo exactly s E(wo) + (1 - s E(wo)) base for an opaque dielectric:
// never above one.
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
    // The specular layer's Fresnel term s F for a microfacet seen at cos_om from one side.
    float LayerFresnel(float cos_om, bool outside) const;
    // IOR on the far side of the interface over the IOR on wo's side.
    float RelativeEta(const Vec3& wo) const { return wo.z > 0 ? ior_ : 1 / ior_; }

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

    Rgb base_;
    float metallic_, specular_, transmission_, ior_, f0_;
    bool refracts_;  // a solid's interface (thickness > 0) with transmission
    MicrofacetDistribution distribution_;
    const GgxAlbedo* albedo_;
    GgxAlbedo::Roughness albedo_roughness_;
    float diffuse_scale_;  // (1 - metallic) (1 - transmission) / (pi (1 - s E_avg))
    ClearcoatLobe coat_;
    SheenLobe sheen_;
};

}  // namespace lf
