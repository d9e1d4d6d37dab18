// Directional albedo E(mu) of a GGX reflection lobe with Schlick's Fresnel, tabulated once per
// process. Schlick's F is linear in F0, F = F0 (1 - x^5) + x^5 with x = 1 - cos, so two tables
// over (cos theta_o, perceptual roughness) give E for every F0: E = F0 A + B.
// The principled BSDF scales its diffuse base by 1 - E so that base and specular layer together
// never reflect more than arrives.
#pragma once

#include <vector>

namespace lf {

class GgxAlbedo {
  public:
    // The table, computed on first use (about 5 M microfacet samples over TBB's threads).
    static const GgxAlbedo& Get();

    // A position on the roughness axis, found once per BSDF rather than per lookup.
    struct Roughness {
        int index = 0;
        float frac = 0;
    };
    // r is glTF's perceptual roughness, GGX alpha = max(r^2, MicrofacetDistribution::kMinAlpha);
    // clamped to [0, 1].
    static Roughness At(float r);

    // E(mu) for Schlick F0 f0, mu = cos theta_o in [0, 1]: bilinear in (mu, r) between nodes that
    // crowd towards grazing (mu = s^2, s uniform).
    float E(float mu, Roughness r, float f0) const;
    // Cosine-weighted hemispherical average 2 int_0^1 E(mu) mu dmu of exactly the function E
    // interpolates, so that a lobe normalised by it integrates to what it should.
    float Average(Roughness r, float f0) const;

    static constexpr int kMuSize = 64;
    static constexpr int kRoughnessSize = 48;

  private:
    GgxAlbedo();

    // Per roughness node, per mu node: the F0 and constant parts of E.
    std::vector<float> a_, b_;
    std::vector<float> a_average_, b_average_;  // per roughness node
};

}  // namespace lf
