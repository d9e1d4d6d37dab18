// The part of a Lambertian base glTF's fresnel_mix (its Appendix B) hands to the specular layer:
// Q(mu) = int (1 - wo.h)^5 cos_i / pi dwi over the hemisphere, h the half vector of wo and wi,
// mu = cos theta_o. With Schlick's F the base weighted by 1 - s F(wo.h) reflects
// 1 - s (F0 + (1 - F0) Q(mu)) of a white base; h does not depend on the roughness, so one curve
// serves every material. Tabulated once per process.
#pragma once

#include <vector>

namespace lf {

class FresnelMixAlbedo {
  public:
    static const FresnelMixAlbedo& Get();

    // Q(mu) for mu in [0, 1], linear between nodes.
    float Q(float mu) const;
    // The directional albedo of the base's weight 1 - s F(wo.h), s F = s Schlick(f0, .).
    float Albedo(float mu, float s, float f0) const { return 1 - s * (f0 + (1 - f0) * Q(mu)); }

    static constexpr int kMuSize = 65;

  private:
    FresnelMixAlbedo();
    std::vector<float> q_;
};

}  // namespace lf
