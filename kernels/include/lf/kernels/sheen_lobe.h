// KHR_materials_sheen's lobe (Estevez and Kulla 2017, as the extension specifies it): the
// "Charlie" distribution D(h) = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi), a = r^2, with the
// extension's visibility V = 1 / ((1 + L(cos_o) + L(cos_i)) 4 cos_o cos_i) clamped to [0, 1]
// (L its fitted Lambda), f = colour D V, no Fresnel, divided by the lobe's directional albedo E
// where that exceeds 1 (smooth sheens at grazing angles; see Eval). Beneath it the base is scaled
// by Keep, the extension's albedo scaling with the lobe's directional albedo E (a table computed on
// first use). Sampled with cosine-weighted directions: the lobe is broad. Directions in the upper
// hemisphere of the shading frame.
#pragma once

#include <vector>

#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

class SheenLobe {
  public:
    // colour in [0, 1]^3 (sheenColorFactor times its texture), roughness glTF's perceptual
    // sheenRoughness in [0, 1].
    SheenLobe(const Rgb& color, float roughness);

    bool active() const { return max_color_ > 0; }
    Rgb Eval(const Vec3& wo, const Vec3& wi) const;
    static float Pdf(const Vec3& wi);
    static Vec3 Sample(const Vec2& u);
    // What the lobe reflects of light arriving from w, in its brightest channel.
    float Albedo(const Vec3& w) const;
    // The share left to the base for the pair: 1 - max(colour) max(E(cos_o), E(cos_i)), the
    // extension's albedo scaling made symmetric (reciprocal) and at most 1 - Albedo(wo).
    float Keep(const Vec3& wo, const Vec3& wi) const;

    // The uncoloured lobe D V, and its directional albedo by brute force (for the table and its
    // test).
    static float Value(const Vec3& wo, const Vec3& wi, float alpha);
    static double IntegrateAlbedo(float mu, float roughness, int quadrature);
    // The table's E(mu) at perceptual roughness r, interpolated.
    static float TabulatedAlbedo(float mu, float roughness);

  private:
    Rgb color_;
    float max_color_;
    float roughness_;
    float alpha_;
};

}  // namespace lf
