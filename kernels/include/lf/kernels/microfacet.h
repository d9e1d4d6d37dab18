// Isotropic microfacet distributions, Trowbridge–Reitz (GGX) and Beckmann, with Smith
// masking-shadowing. Everything lives in the upper hemisphere of a local frame whose +z is the
// macro-surface normal: callers mirror back-side directions to the front first.
#pragma once

#include "lf/core/scene.h"
#include "lf/core/vec.h"

namespace lf {

class MicrofacetDistribution {
  public:
    // Narrower lobes are mirrors in all but name, yet float rounding of a recomputed half vector
    // (~1e-7 rad) would become a sizeable fraction of their width and D's 1/(pi alpha^2) peak
    // would keep growing without bound.
    static constexpr float kMinAlpha = 1e-3f;

    MicrofacetDistribution(Material::Distribution type, float alpha);

    float alpha() const { return alpha_; }

    // Density of microfacet normals per solid angle: the integral of D(wm) cos(theta_m) over the
    // hemisphere is 1.
    float D(const Vec3& wm) const;
    // Smith Lambda(w) times |cos theta_w|. Lambda diverges at grazing w, this product does not,
    // so G1 and G are written in terms of it.
    float CosLambda(const Vec3& w) const;
    float G1(const Vec3& w) const;
    // Height-correlated masking-shadowing, 1 / (1 + Lambda(wo) + Lambda(wi)).
    float G(const Vec3& wo, const Vec3& wi) const;
    // G(wo, wi) / (|cos theta_o| |cos theta_i|), which every microfacet BSDF divides by, with G
    // multiplied through so that no grazing direction makes a Lambda infinite. Both cosines
    // must be nonzero.
    float GOverCosines(const Vec3& wo, const Vec3& wi) const;

    // A microfacet normal for wo (wo.z > 0): GGX samples the visible normals (Heitz 2018), whose
    // reflections are all potentially valid; Beckmann samples D(wm) cos(theta_m).
    Vec3 SampleWm(const Vec3& wo, const Vec2& u) const;
    // Solid angle density of SampleWm.
    float PdfWm(const Vec3& wo, const Vec3& wm) const;

  private:
    Material::Distribution type_;
    float alpha_;
};

}  // namespace lf
