// The principled material (glTF 2.0's metallic-roughness BRDF with transmission) against its
// limits, energy conservation, reciprocity and its own density.
#include "lf/kernels/principled_bsdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "bsdf_albedo.h"
#include "chi_square.h"
#include "lf/core/sampler.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/ggx_albedo.h"
#include "lf/kernels/microfacet.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

using testing::Albedo;
using testing::EstimateAlbedo;
using testing::FurnaceDirections;
using testing::Spherical;
using testing::UniformSphere;

struct Params {
    Rgb base{1.0f};
    float roughness = 0.5f;
    float metallic = 0;
    float specular = 1;
    float transmission = 0;
    float thickness = 0;
    float ior = 1.5f;
    float clearcoat = 0, clearcoat_roughness = 0;
    Rgb sheen_color{0.0f};
    float sheen_roughness = 0;
    Rgb specular_color{1.0f};
};

Material Principled(const Params& p) {
    Material m;
    m.type = Material::Type::kPrincipled;
    m.reflectance = p.base;
    m.roughness = p.roughness;
    m.metallic = p.metallic;
    m.specular = p.specular;
    m.specular_color = p.specular_color;
    m.transmission = p.transmission;
    m.thickness = p.thickness;
    m.ior = p.ior;
    m.clearcoat = p.clearcoat;
    m.clearcoat_roughness = p.clearcoat_roughness;
    m.sheen_color = p.sheen_color;
    m.sheen_roughness = p.sheen_roughness;
    return m;
}

std::string Describe(const Params& p) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "r %.2f metallic %.2f specular %.2f transmission %.2f %s coat %.2f (r %.2f) "
                  "sheen %.2f (r %.2f)",
                  p.roughness, p.metallic, p.specular, p.transmission,
                  p.transmission > 0 ? (p.thickness > 0 ? "solid" : "thin") : "opaque", p.clearcoat,
                  p.clearcoat_roughness, p.sheen_color.Average(), p.sheen_roughness);
    return text;
}

Params Layered(Params p, float clearcoat, float clearcoat_roughness, const Rgb& sheen_color,
               float sheen_roughness) {
    p.clearcoat = clearcoat;
    p.clearcoat_roughness = clearcoat_roughness;
    p.sheen_color = sheen_color;
    p.sheen_roughness = sheen_roughness;
    return p;
}

// A spread of materials: opaque, metallic, thin and solid transmission, tinted, and the same
// under a clear coat, a sheen or both.
std::vector<Params> Spread() {
    const Params plastic{Rgb(0.8f, 0.4f, 0.2f), 0.5f};
    const Params thin{Rgb(0.7f, 0.8f, 0.9f), 0.4f, 0, 1, 1, 0};
    const Params solid{Rgb(1.0f), 0.3f, 0, 1, 1, 1};
    return {
        Layered(plastic, 1, 0.1f, Rgb(0.0f), 0),
        Layered(plastic, 0, 0, Rgb(0.9f, 0.7f, 0.5f), 0.5f),
        Layered(Params{Rgb(0.95f, 0.7f, 0.4f), 0.6f, 1}, 0.7f, 0.4f, Rgb(0.3f), 0.2f),
        Layered(thin, 1, 0.3f, Rgb(0.5f, 0.6f, 0.7f), 0.8f),
        Layered(solid, 0.8f, 0.05f, Rgb(0.0f), 0),
        {Rgb(0.8f, 0.4f, 0.2f), 0.5f},
        {Rgb(0.9f, 0.6f, 0.3f), 0.3f, 0.5f},
        {Rgb(0.95f, 0.7f, 0.4f), 0.6f, 1},
        {Rgb(0.7f, 0.8f, 0.9f), 0.4f, 0, 1, 1, 0},
        {Rgb(0.5f), 0.7f, 0.2f, 0.6f, 0.5f, 0},
        {Rgb(1.0f), 0.3f, 0, 1, 1, 1},
        {Rgb(0.6f, 0.9f, 0.6f), 0.5f, 0.2f, 1, 0.6f, 2, 1.33f},
        // KHR_materials_specular's colour, one channel's F0 clamped at 1.
        {Rgb(0.8f, 0.4f, 0.2f), 0.4f, 0, 0.8f, 0, 0, 2.5f, 0, 0, Rgb(0.0f), 0, Rgb(6, 1, 0.3f)},
        {Rgb(0.7f, 0.8f, 0.9f), 0.3f, 0, 1, 1, 1, 1.5f, 0, 0, Rgb(0.0f), 0, Rgb(2, 0.5f, 1)},
    };
}

// ---------------------------------------------------------------------------------------------
// The albedo table the diffuse base is scaled by.

// E(mu) by brute force: a fine midpoint grid over GGX visible normals.
double ReferenceE(float mu, float r, float f0) {
    const MicrofacetDistribution d(Material::Distribution::kGgx, r * r);
    const Vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
    constexpr int n = 512;
    double sum = 0;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const Vec3 wm = d.SampleWm(wo, Vec2((x + 0.5f) / n, (y + 0.5f) / n));
            const float c = Dot(wo, wm);
            const Vec3 wi = wm * (2 * c) - wo;
            if (c <= 0 || wi.z <= 0) continue;
            const double m = 1 - std::min(1.0f, c);
            sum += d.G(wo, wi) / d.G1(wo) * (f0 + (1 - f0) * m * m * m * m * m);
        }
    }
    return sum / (double(n) * n);
}

// Between nodes, where interpolation errs most. An E too high only darkens the diffuse base a
// little; too low would let base and layer together reflect more than arrives.
TEST(GgxAlbedo, MatchesBruteForceBetweenNodes) {
    const GgxAlbedo& table = GgxAlbedo::Get();
    for (float r : {0.05f, 0.0748f, 0.37f, 0.81f}) {
        for (float mu : {0.0215f, 0.03f, 0.41f, 0.93f}) {
            for (float f0 : {0.0f, 0.04f, 0.25f}) {  // IOR 1 to 3
                const double e = table.E(mu, GgxAlbedo::At(r), f0), ref = ReferenceE(mu, r, f0);
                EXPECT_LE(ref - e, 2.5e-3) << "r " << r << " mu " << mu << " f0 " << f0;
                EXPECT_LE(e - ref, 5e-3) << "r " << r << " mu " << mu << " f0 " << f0;
            }
        }
    }
}

// GGX with alpha = 1 at normal incidence reflects 1 - ln 2 (see bsdf_test's closed form).
TEST(GgxAlbedo, RoughNormalIncidenceIsOneMinusLn2) {
    EXPECT_NEAR(GgxAlbedo::Get().E(1, GgxAlbedo::At(1), 1), 1 - std::numbers::ln2, 1e-4);
}

TEST(GgxAlbedo, AverageIsTheCosineWeightedIntegral) {
    const GgxAlbedo& table = GgxAlbedo::Get();
    for (float r : {0.1f, 0.5f, 1.0f}) {
        const auto at = GgxAlbedo::At(r);
        double sum = 0;
        constexpr int n = 100000;
        for (int i = 0; i < n; ++i) {
            const float mu = (i + 0.5f) / n;
            sum += 2 * table.E(mu, at, 0.04f) * mu / n;
        }
        EXPECT_NEAR(table.Average(at, 0.04f), sum, 1e-5) << r;
    }
}

// ---------------------------------------------------------------------------------------------
// White furnace: base colour 1, every roughness and metallic, never above one.

TEST(PrincipledBsdf, WhiteFurnaceNeverExceedsOne) {
    int cases = 0;
    double highest = 0;
    std::string highest_case;
    for (float roughness : {0.01f, 0.1f, 0.3f, 0.6f, 1.0f}) {
        for (float metallic : {0.0f, 0.5f, 1.0f}) {
            for (auto [transmission, thickness] :
                 {std::pair(0.0f, 0.0f), std::pair(1.0f, 0.0f), std::pair(0.5f, 0.0f),
                  std::pair(1.0f, 1.0f), std::pair(0.5f, 1.0f)}) {
                Params p;
                p.roughness = roughness;
                p.metallic = metallic;
                p.transmission = transmission;
                p.thickness = thickness;
                const Bsdf bsdf(Principled(p));
                for (const Vec3& wo : FurnaceDirections()) {
                    const Albedo a = EstimateAlbedo(bsdf, wo, 71 + uint64_t(cases), 20000);
                    ++cases;
                    if (a.mean.g > highest) {
                        highest = a.mean.g;
                        highest_case = Describe(p) + " cos " + std::to_string(wo.z);
                    }
                    EXPECT_LE(a.mean.g, 1 + 4 * a.stderr_.g) << Describe(p) << " cos " << wo.z;
                    // An opaque white dielectric loses only what glTF's single-scattering mix
                    // loses, and what the base gives up where that mix would exceed one
                    // (smooth, near normal incidence: 0.955).
                    if (metallic == 0 && transmission == 0) {
                        EXPECT_GT(a.mean.g, 0.95 - 4 * a.stderr_.g)
                            << Describe(p) << " cos " << wo.z;
                    }
                    // Nearly smooth glass loses nothing either: what is not reflected is
                    // transmitted (from inside a solid, beyond the critical angle, reflected).
                    if (metallic == 0 && transmission == 1 && roughness <= 0.1f &&
                        std::abs(wo.z) >= 0.3f) {
                        EXPECT_GT(a.mean.g, 0.99 - 4 * a.stderr_.g)
                            << Describe(p) << " cos " << wo.z;
                    }
                }
            }
        }
    }
    std::printf("[furnace] %d cases, highest albedo %.5f (%s)\n", cases, highest,
                highest_case.c_str());
}

// ---------------------------------------------------------------------------------------------
// Sampling.

struct Chi2Case {
    std::string name;
    Params params;
    Vec3 wo;
};

std::vector<Chi2Case> Chi2Cases() {
    const std::vector<std::string> names = {
        "CoatedPlastic", "Sheen",   "CoatedSheenMetal", "CoatedSheenThinGlass",
        "CoatedSolid",   "Plastic", "HalfMetal",        "Metal",
        "ThinGlass",     "ThinMix", "SolidGlass",       "SolidMix",
    };
    std::vector<std::pair<std::string, Params>> materials;
    for (size_t i = 0; i < names.size(); ++i) materials.push_back({names[i], Spread()[i]});
    std::vector<Chi2Case> cases;
    for (const auto& [m_name, params] : materials) {
        // Back130 starts inside the solids.
        for (const auto& [wo_name, wo] : testing::Chi2IncidentDirections()) {
            cases.push_back({m_name + "_" + wo_name, params, wo});
        }
    }
    return cases;
}

class PrincipledChi2 : public ::testing::TestWithParam<Chi2Case> {};

TEST_P(PrincipledChi2, SampleMatchesPdf) {
    const Chi2Case& c = GetParam();
    testing::ExpectSamplingMatchesPdf(Bsdf(Principled(c.params)), c.wo, c.name,
                                      int(Chi2Cases().size()));
}

INSTANTIATE_TEST_SUITE_P(Lobes, PrincipledChi2, ::testing::ValuesIn(Chi2Cases()),
                         [](const auto& info) { return info.param.name; });

TEST(PrincipledBsdf, SampleAgreesWithEvalAndPdf) {
    int checked = 0, transmitted = 0;
    const std::vector<Params> spread = Spread();
    for (size_t m = 0; m < spread.size(); ++m) {
        const Material material = Principled(spread[m]);
        const Bsdf bsdf(material);
        for (int i = 0; i < 20000; ++i) {
            Sampler sampler(73, int(m), 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D());
            const float uc = sampler.Get1D();
            const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, sampler.Get2D());
            if (!bs) continue;
            ++checked;
            EXPECT_FALSE(bs->delta);
            EXPECT_NEAR(Length(bs->wi), 1, 1e-5);
            const float pdf = bsdf.Pdf(wo, bs->wi);
            EXPECT_NEAR(bs->pdf, pdf, 1e-5 * pdf) << Describe(spread[m]);
            const Rgb f = bsdf.Eval(wo, bs->wi);
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(bs->f[ch], f[ch], 1e-5 * f[ch]);
            if (bs->wi.z * wo.z < 0) {
                ++transmitted;
                // Only a solid's interface bends light; the path tracer gets its IOR ratio.
                const bool solid = material.thickness > 0;
                const float eta = solid ? (wo.z > 0 ? material.ior : 1 / material.ior) : 1;
                EXPECT_FLOAT_EQ(bs->eta, eta) << Describe(spread[m]);
            } else {
                EXPECT_EQ(bs->eta, 1);
            }
        }
    }
    EXPECT_GT(checked, 100000);
    EXPECT_GT(transmitted, 10000);
}

// ---------------------------------------------------------------------------------------------
// Limits: smooth glass, lambert and the GGX conductor.

// At roughness 0 the lobes collapse onto the mirror and refraction directions: a thin wall
// lets light straight through, a solid bends it by Snell's law, and the share reflected is
// Fresnel's (Schlick with F0 from the IOR).
TEST(PrincipledBsdf, SmoothGlassReflectsAndRefractsLikeADielectric) {
    for (float thickness : {0.0f, 1.0f}) {
        Params p;
        p.roughness = 0;
        p.transmission = 1;
        p.thickness = thickness;
        const Bsdf bsdf(Principled(p));
        const float f0 = 0.04f;
        for (float cos : {0.9f, 0.6f, 0.3f}) {
            const Vec3 wo = Spherical(std::acos(cos), 0.4);
            constexpr int n = 20000;
            // GGX's tails are long even at the smallest alpha (1e-3): most, not all, samples lie
            // within 0.02 rad of the ideal direction.
            constexpr float kNear = 0.9998f;
            int reflected = 0, near_ideal = 0;
            for (int i = 0; i < n; ++i) {
                Sampler sampler(97, 0, 0, uint64_t(i));
                const float uc = sampler.Get1D();
                const auto bs = bsdf.Sample(wo, uc, sampler.Get2D());
                if (!bs) continue;  // a far tail's facet sends it below the horizon
                Vec3 ideal;
                if (bs->wi.z > 0) {
                    ++reflected;
                    ideal = Vec3(-wo.x, -wo.y, wo.z);
                } else if (thickness == 0) {
                    ideal = -wo;
                } else {
                    // Snell: the tangential component shrinks by the IOR, azimuth turned by pi.
                    const Vec3 t = Vec3(-wo.x, -wo.y, 0) / p.ior;
                    ideal = t + Vec3(0, 0, -std::sqrt(1 - LengthSquared(t)));
                }
                if (Dot(bs->wi, ideal) > kNear) ++near_ideal;
            }
            EXPECT_GT(near_ideal, 0.95 * n) << thickness << " " << cos;
            // Samples are picked in proportion to the lobes' energy, up to the pick's
            // approximation of it: compare the energy itself.
            const Albedo a = EstimateAlbedo(bsdf, wo, 101, n);
            const double fresnel = f0 + (1 - f0) * std::pow(1 - cos, 5);
            EXPECT_GT(reflected, 0);
            EXPECT_NEAR(a.mean.g, 1, 4 * a.stderr_.g + 2e-3) << thickness << " " << cos;
            double reflected_energy = 0;
            for (int i = 0; i < n; ++i) {
                Sampler sampler(101, 0, 0, uint64_t(i));
                const float uc = sampler.Get1D();
                const auto bs = bsdf.Sample(wo, uc, sampler.Get2D());
                if (bs && bs->wi.z > 0) reflected_energy += bs->f.g * bs->wi.z / bs->pdf;
            }
            EXPECT_NEAR(reflected_energy / n, fresnel, 5e-3) << thickness << " " << cos;
        }
    }
}

// glTF 2.0's Appendix B for a dielectric: fresnel_mix(1.5, diffuse, specular) =
// (1 - F) base / pi + F D Vis, F = 0.04 + 0.96 (1 - V.H)^5, D and Vis GGX's with
// alpha = r^2 (height-correlated Smith), at angles and roughnesses where that mix conserves
// energy.
TEST(PrincipledBsdf, DielectricIsAppendixBFresnelMix) {
    constexpr double kDeg = std::numbers::pi / 180;
    const float base = 0.5f;
    int compared = 0;
    for (float r : {0.7f, 0.85f, 1.0f}) {
        Params p;
        p.base = Rgb(base);
        p.roughness = r;
        const Bsdf bsdf(Principled(p));
        const float a2 = r * r * r * r;
        for (float theta_o : {0.0f, 20.0f, 45.0f}) {
            for (float theta_i : {0.0f, 30.0f, 50.0f}) {
                for (float phi : {0.0f, 90.0f, 180.0f}) {
                    const Vec3 v = Spherical(theta_o * kDeg, 0.0);
                    const Vec3 l = Spherical(theta_i * kDeg, phi * kDeg);
                    const Vec3 h = Normalize(v + l);
                    const float vh = Dot(v, h), nh = h.z, nl = l.z, nv = v.z;
                    const float f = 0.04f + 0.96f * std::pow(1 - vh, 5.0f);
                    const float dd = nh * nh * (a2 - 1) + 1;
                    const float d = a2 / (std::numbers::pi_v<float> * dd * dd);
                    const float vis = 0.5f / (nl * std::sqrt(nv * nv * (1 - a2) + a2) +
                                              nv * std::sqrt(nl * nl * (1 - a2) + a2));
                    const float expected =
                        (1 - f) * base * std::numbers::inv_pi_v<float> + f * d * vis;
                    const Rgb got = bsdf.Eval(v, l);
                    EXPECT_NEAR(got.g, expected, 2e-6f * expected)
                        << "r " << r << " theta_o " << theta_o << " theta_i " << theta_i << " phi "
                        << phi;
                    ++compared;
                }
            }
        }
    }
    EXPECT_EQ(compared, 81);
}

// KHR_materials_specular's colour: per channel c, F_c = F0_c + (1 - F0_c)(1 - V.H)^5 with
// F0_c = min(F0(ior) colour_c, 1), and f_c = s F_c D Vis + (1 - s max_c F_c) base / pi, at
// angles, roughnesses and colours (one clamped at F0 = 1) where the mix conserves energy.
TEST(PrincipledBsdf, SpecularColorIsTheExtensionsFresnelMix) {
    constexpr double kDeg = std::numbers::pi / 180;
    const float base = 0.5f;
    struct Tint {
        float ior, specular;
        Rgb color;
    };
    int compared = 0;
    for (const Tint& tint :
         {Tint{1.5f, 1.0f, Rgb(1.0f, 0.5f, 0.2f)}, Tint{1.5f, 0.6f, Rgb(2.0f, 0.0f, 1.0f)},
          Tint{2.5f, 0.5f, Rgb(6.0f, 1.0f, 0.3f)}}) {
        const float f0 = ((tint.ior - 1) / (tint.ior + 1)) * ((tint.ior - 1) / (tint.ior + 1));
        for (float r : {0.7f, 1.0f}) {
            Params p;
            p.base = Rgb(base);
            p.roughness = r;
            p.ior = tint.ior;
            p.specular = tint.specular;
            p.specular_color = tint.color;
            const Bsdf bsdf(Principled(p));
            const float a2 = r * r * r * r;
            for (float theta_o : {0.0f, 30.0f, 50.0f}) {
                for (float theta_i : {10.0f, 40.0f}) {
                    for (float phi : {0.0f, 180.0f}) {
                        const Vec3 v = Spherical(theta_o * kDeg, 0.0);
                        const Vec3 l = Spherical(theta_i * kDeg, phi * kDeg);
                        const Vec3 h = Normalize(v + l);
                        const float vh = Dot(v, h), nh = h.z, nl = l.z, nv = v.z;
                        const float dd = nh * nh * (a2 - 1) + 1;
                        const float d = a2 / (std::numbers::pi_v<float> * dd * dd);
                        const float vis = 0.5f / (nl * std::sqrt(nv * nv * (1 - a2) + a2) +
                                                  nv * std::sqrt(nl * nl * (1 - a2) + a2));
                        float fresnel[3], max_fresnel = 0;
                        for (int c = 0; c < 3; ++c) {
                            const float f0c = std::min(f0 * tint.color[c], 1.0f);
                            fresnel[c] = f0c + (1 - f0c) * std::pow(1 - vh, 5.0f);
                            max_fresnel = std::max(max_fresnel, fresnel[c]);
                        }
                        const Rgb got = bsdf.Eval(v, l);
                        for (int c = 0; c < 3; ++c) {
                            const float expected = tint.specular * fresnel[c] * d * vis +
                                                   (1 - tint.specular * max_fresnel) * base *
                                                       std::numbers::inv_pi_v<float>;
                            EXPECT_NEAR(got[c], expected, 2e-6f * expected)
                                << "ior " << tint.ior << " channel " << c << " r " << r
                                << " theta_o " << theta_o << " theta_i " << theta_i << " phi "
                                << phi;
                        }
                        ++compared;
                    }
                }
            }
        }
    }
    EXPECT_EQ(compared, 72);
}

// Issue 28's plane: base 0.5, roughness 1, irradiance pi at normal incidence, seen head on:
// (1 - F0) 0.5 + F0 D Vis pi = 0.48 + 0.04 / pi * 0.25 * pi = 0.490.
TEST(PrincipledBsdf, RoughBaseHeadOnIsAppendixBValue) {
    Params p;
    p.base = Rgb(0.5f);
    p.roughness = 1;
    const Bsdf bsdf(Principled(p));
    const Vec3 n(0, 0, 1);
    EXPECT_NEAR(bsdf.Eval(n, n).g * std::numbers::pi_v<float>, 0.49f, 1e-6f);
}

TEST(PrincipledBsdf, WithoutSpecularMetalOrTransmissionIsLambert) {
    Params p;
    p.base = Rgb(0.2f, 0.5f, 0.8f);
    p.specular = 0;
    Material lambert;
    lambert.reflectance = p.base;
    for (float roughness : {0.0f, 0.4f, 1.0f}) {
        p.roughness = roughness;
        const Bsdf principled(Principled(p)), reference(lambert);
        for (int i = 0; i < 5000; ++i) {
            Sampler sampler(79, 0, 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D()), wi = UniformSphere(sampler.Get2D());
            EXPECT_EQ(principled.Eval(wo, wi), reference.Eval(wo, wi));
            EXPECT_EQ(principled.Pdf(wo, wi), reference.Pdf(wo, wi));
            const float uc = sampler.Get1D();
            const Vec2 u = sampler.Get2D();
            const auto a = principled.Sample(wo, uc, u), b = reference.Sample(wo, uc, u);
            ASSERT_EQ(a.has_value(), b.has_value());
            if (!a) continue;
            EXPECT_EQ(a->wi, b->wi);
            EXPECT_EQ(a->f, b->f);
            EXPECT_EQ(a->pdf, b->pdf);
        }
    }
}

TEST(PrincipledBsdf, FullyMetallicIsTheSchlickGgxConductor) {
    for (float roughness : {0.05f, 0.3f, 0.7f, 1.0f}) {
        Params p;
        p.base = Rgb(0.95f, 0.64f, 0.54f);
        p.roughness = roughness;
        p.metallic = 1;
        p.transmission = 0.5f;  // blended away with the rest of the dielectric
        Material glossy;
        glossy.type = Material::Type::kGlossy;
        glossy.reflectance = p.base;
        glossy.roughness = roughness * roughness;
        const Bsdf principled(Principled(p)), reference(glossy);
        int nonzero = 0;
        for (int i = 0; i < 5000; ++i) {
            Sampler sampler(83, 0, 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D()), wi = UniformSphere(sampler.Get2D());
            const Rgb a = principled.Eval(wo, wi), b = reference.Eval(wo, wi);
            if (!b.IsBlack()) ++nonzero;
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(a[c], b[c], 1e-5f * b[c] + std::numeric_limits<float>::min())
                    << "r " << roughness;
            }
            const float pa = principled.Pdf(wo, wi), pb = reference.Pdf(wo, wi);
            EXPECT_NEAR(pa, pb, 1e-5f * pb) << "r " << roughness;
        }
        EXPECT_GT(nonzero, 2000);
    }
}

// ---------------------------------------------------------------------------------------------
// Reciprocity: reflection (and the thin wall's straight-through transmission) is symmetric;
// refraction obeys f(wo, wi) eta^2 = f(wi, wo), eta the IOR on wi's side over wo's.

TEST(PrincipledBsdf, Reciprocity) {
    const std::vector<Params> spread = Spread();
    for (size_t m = 0; m < spread.size(); ++m) {
        const Material material = Principled(spread[m]);
        const Bsdf bsdf(material);
        const bool solid = material.transmission > 0 && material.thickness > 0;
        int reflected = 0, refracted = 0;
        for (int i = 0; i < 40000; ++i) {
            Sampler sampler(89, int(m), 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D()), wi = UniformSphere(sampler.Get2D());
            const Rgb a = bsdf.Eval(wo, wi), b = bsdf.Eval(wi, wo);
            ASSERT_TRUE(a.IsFinite());
            float scale = 1;
            if (wo.z * wi.z < 0 && solid) {
                const float eta = wo.z > 0 ? material.ior : 1 / material.ior;
                scale = eta * eta;
                if (!a.IsBlack()) ++refracted;
            } else if (!a.IsBlack()) {
                ++reflected;
            }
            for (int c = 0; c < 3; ++c) {
                // Near the critical angle the half vector's rounding dominates 1 - F, which is
                // tiny there: the absolute floor.
                EXPECT_NEAR(a[c] * scale, b[c], 2e-4f * std::max(a[c] * scale, b[c]) + 1e-7f)
                    << Describe(spread[m]) << " wo " << wo.z << " wi " << wi.z;
            }
        }
        EXPECT_GT(reflected, 1000) << Describe(spread[m]);
        if (solid) {
            EXPECT_GT(refracted, 1000) << Describe(spread[m]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Robustness.

TEST(PrincipledBsdf, NeverReturnsNonFinite) {
    std::vector<Params> params;
    for (float r :
         {0.0f, 1e-4f, 0.5f, 1.0f, 7.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()}) {
        for (auto [t, thickness, ior] : {std::tuple(0.0f, 0.0f, 1.5f), std::tuple(1.0f, 0.0f, 1.5f),
                                         std::tuple(1.0f, 1.0f, 1.5f), std::tuple(1.0f, 1.0f, 1.0f),
                                         std::tuple(0.7f, 1.0f, 3.0f)}) {
            Params p;
            p.base = Rgb(1.0f, 0.0f, 0.5f);
            p.roughness = r;
            p.metallic = 0.3f;
            p.transmission = t;
            p.thickness = thickness;
            p.ior = ior;
            params.push_back(p);
        }
    }
    std::vector<Vec3> wos;
    for (float z : {0.0f, 1e-8f, 1e-6f, 1e-4f, 0.01f, 0.5f, 1.0f}) {
        const float s = std::sqrt(1 - z * z);
        for (Vec3 w : {Vec3(s, 0, z), Vec3(0.6f * s, 0.8f * s, z)}) {
            wos.push_back(w);
            wos.push_back(Vec3(w.x, w.y, -w.z));
        }
    }
    const std::vector<float> us = {0.0f, 1e-7f, 0.5f, 0.999f, 1 - 0x1p-24f};
    for (const Params& p : params) {
        const Bsdf bsdf(Principled(p));
        for (const Vec3& wo : wos) {
            for (float u0 : us) {
                for (float u1 : us) {
                    for (float uc : us) {
                        const auto bs = bsdf.Sample(wo, uc, {u0, u1});
                        if (!bs) continue;
                        EXPECT_TRUE(bs->f.IsFinite()) << Describe(p);
                        EXPECT_GE(std::min({bs->f.r, bs->f.g, bs->f.b}), 0) << Describe(p);
                        EXPECT_TRUE(std::isfinite(bs->pdf) && bs->pdf > 0) << Describe(p);
                        EXPECT_NEAR(Length(bs->wi), 1, 1e-5f) << Describe(p);
                    }
                }
            }
            for (const Vec3& wi : wos) {
                EXPECT_TRUE(bsdf.Eval(wo, wi).IsFinite()) << Describe(p);
                const float pdf = bsdf.Pdf(wo, wi);
                EXPECT_TRUE(std::isfinite(pdf) && pdf >= 0) << Describe(p);
            }
        }
    }
}

}  // namespace
}  // namespace lf
