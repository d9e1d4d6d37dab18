#include "lf/kernels/bsdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "bsdf_albedo.h"
#include "chi_square.h"
#include "lf/core/sampler.h"
#include "lf/kernels/fresnel.h"
#include "lf/kernels/microfacet.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

using testing::Albedo;
using testing::ChiSquarePValue;
using testing::EstimateAlbedo;
using testing::FurnaceDirections;
using testing::Integrate1D;
using testing::kFurnaceSamples;
using testing::kPi;
using testing::Radians;
using testing::Spherical;
using testing::UniformSphere;

Material Lambert(Rgb rho) {
    Material m;
    m.type = Material::Type::kLambert;
    m.reflectance = rho;
    return m;
}

Material Mirror(Rgb r) {
    Material m;
    m.type = Material::Type::kMirror;
    m.reflectance = r;
    return m;
}

Material Glossy(Material::Distribution d, float alpha, Rgb f0 = Rgb(1.0f)) {
    Material m;
    m.type = Material::Type::kGlossy;
    m.distribution = d;
    m.roughness = alpha;
    m.reflectance = f0;
    return m;
}

// Gold at roughly 650, 550 and 450 nm.
Material Gold(Material::Distribution d, float alpha) {
    Material m = Glossy(d, alpha);
    m.conductor = true;
    m.eta = Rgb(0.18f, 0.42f, 1.37f);
    m.k = Rgb(3.42f, 2.35f, 1.77f);
    return m;
}

Material Dielectric(float ior) {
    Material m;
    m.type = Material::Type::kDielectric;
    m.ior = ior;
    return m;
}

constexpr auto kGgx = Material::Distribution::kGgx;
constexpr auto kBeckmann = Material::Distribution::kBeckmann;

TEST(Chi2Helper, MatchesClosedForms) {
    for (double x : {0.1, 1.0, 3.0, 10.0, 40.0}) {
        EXPECT_NEAR(ChiSquarePValue(x, 2), std::exp(-x / 2), 1e-12) << x;
        EXPECT_NEAR(ChiSquarePValue(x, 1), std::erfc(std::sqrt(x / 2)), 1e-12) << x;
    }
    // Median of chi-square with 100 degrees of freedom is about 99.334.
    EXPECT_NEAR(ChiSquarePValue(99.3341, 100), 0.5, 1e-4);
}

// ---------------------------------------------------------------------------------------------
// Chi-square goodness of fit of Sample against Pdf.

struct Chi2Case {
    std::string name;
    Material material;
    Vec3 wo;
};

std::vector<Chi2Case> Chi2Cases() {
    std::vector<Chi2Case> cases;
    for (const auto& [wo_name, wo] : testing::Chi2IncidentDirections()) {
        cases.push_back({"Lambert_" + wo_name, Lambert(Rgb(0.5f)), wo});
        for (auto [d, d_name] : {std::pair(kGgx, "Ggx"), std::pair(kBeckmann, "Beckmann")}) {
            for (auto [alpha, a_name] : {std::pair(0.05f, "005"), std::pair(0.2f, "020"),
                                         std::pair(0.5f, "050"), std::pair(1.0f, "100")}) {
                cases.push_back({std::string(d_name) + a_name + "_" + wo_name,
                                 Glossy(d, alpha, Rgb(0.9f, 0.5f, 0.2f)), wo});
            }
        }
    }
    return cases;
}

class BsdfChi2 : public ::testing::TestWithParam<Chi2Case> {};

TEST_P(BsdfChi2, SampleMatchesPdf) {
    const Chi2Case& c = GetParam();
    testing::ExpectSamplingMatchesPdf(Bsdf(c.material), c.wo, c.name, int(Chi2Cases().size()));
}

INSTANTIATE_TEST_SUITE_P(AllNonDelta, BsdfChi2, ::testing::ValuesIn(Chi2Cases()),
                         [](const auto& info) { return info.param.name; });

TEST(Bsdf, SampleAgreesWithEvalAndPdf) {
    const std::vector<Material> materials = {
        Lambert(Rgb(0.3f, 0.6f, 0.9f)), Glossy(kGgx, 0.3f, Rgb(0.9f, 0.5f, 0.2f)),
        Glossy(kBeckmann, 0.3f),        Gold(kGgx, 0.1f),
        Gold(kBeckmann, 0.7f),          Glossy(kGgx, 0.0f),
    };
    int checked = 0;
    for (size_t m = 0; m < materials.size(); ++m) {
        const Bsdf bsdf(materials[m]);
        for (int i = 0; i < 20000; ++i) {
            Sampler sampler(11, int(m), 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D());
            const float uc = sampler.Get1D();
            const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, sampler.Get2D());
            if (!bs) continue;
            ++checked;
            EXPECT_GT(bs->wi.z * wo.z, 0) << "reflection sampled onto the other side";
            EXPECT_NEAR(Length(bs->wi), 1, 1e-5);
            const float pdf = bsdf.Pdf(wo, bs->wi);
            EXPECT_NEAR(bs->pdf, pdf, 1e-5 * pdf) << m;
            const Rgb f = bsdf.Eval(wo, bs->wi);
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(bs->f[ch], f[ch], 1e-5 * f[ch]) << m;
        }
    }
    EXPECT_GT(checked, 100000);
}

// ---------------------------------------------------------------------------------------------
// Reciprocity.

TEST(Bsdf, Reciprocity) {
    std::vector<Material> materials = {Lambert(Rgb(0.2f, 0.5f, 0.8f))};
    for (auto d : {kGgx, kBeckmann}) {
        for (float alpha : {0.05f, 0.3f, 1.0f}) {
            materials.push_back(Glossy(d, alpha, Rgb(0.9f, 0.5f, 0.04f)));
            materials.push_back(Gold(d, alpha));
        }
    }
    for (size_t m = 0; m < materials.size(); ++m) {
        const Bsdf bsdf(materials[m]);
        int nonzero = 0;
        for (int i = 0; i < 20000; ++i) {
            Sampler sampler(23, int(m), 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D());
            const Vec3 wi = UniformSphere(sampler.Get2D());
            const Rgb a = bsdf.Eval(wo, wi), b = bsdf.Eval(wi, wo);
            ASSERT_TRUE(a.IsFinite());
            if (!a.IsBlack()) ++nonzero;
            for (int ch = 0; ch < 3; ++ch) {
                // Subnormal values (far tails of narrow Beckmann lobes) carry no relative
                // precision, hence the absolute floor.
                EXPECT_NEAR(a[ch], b[ch],
                            1e-4f * std::max(a[ch], b[ch]) + std::numeric_limits<float>::min())
                    << "material " << m << " channel " << ch;
            }
        }
        // Same-side pairs are half of all pairs; narrow Beckmann lobes underflow to zero for
        // most of them.
        EXPECT_GT(nonzero, 1000) << m;
    }
}

// ---------------------------------------------------------------------------------------------
// Energy conservation: the directional albedo, the mean of f |cos| / pdf over Sample.

TEST(Bsdf, LambertAlbedoIsReflectance) {
    const Rgb rho(0.2f, 0.5f, 0.8f);
    const Bsdf bsdf(Lambert(rho));
    for (const Vec3& wo : FurnaceDirections()) {
        // Cosine sampling is exact importance sampling: every weight is rho up to rounding.
        const Albedo a = EstimateAlbedo(bsdf, wo, 31, kFurnaceSamples);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(a.mean[c], rho[c], 4 * a.stderr_[c] + 1e-6f) << wo.z;
            EXPECT_LT(a.stderr_[c], 1e-6f);
        }
    }
}

TEST(Bsdf, MirrorReflectsExactly) {
    const Rgb r(0.9f, 0.6f, 0.3f);
    const Bsdf bsdf(Mirror(r));
    EXPECT_TRUE(bsdf.IsDelta());
    for (const Vec3& wo : FurnaceDirections()) {
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, 0.5f, {0.3f, 0.7f});
        ASSERT_TRUE(bs);
        EXPECT_TRUE(bs->delta);
        EXPECT_EQ(bs->pdf, 1);
        EXPECT_EQ(bs->wi, Vec3(-wo.x, -wo.y, wo.z));
        const Rgb w = bs->f * (std::abs(bs->wi.z) / bs->pdf);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(w[c], r[c], 1e-6f) << wo.z;
        EXPECT_TRUE(bsdf.Eval(wo, bs->wi).IsBlack());
        EXPECT_EQ(bsdf.Pdf(wo, bs->wi), 0);
    }
}

TEST(Bsdf, GlossyConservesEnergy) {
    std::vector<Material> materials;
    for (auto d : {kGgx, kBeckmann}) {
        for (float alpha : {0.0f, 0.05f, 0.2f, 0.5f, 1.0f}) {
            materials.push_back(Glossy(d, alpha, Rgb(1.0f)));
            materials.push_back(Gold(d, alpha));
        }
    }
    for (size_t m = 0; m < materials.size(); ++m) {
        const Bsdf bsdf(materials[m]);
        const MicrofacetDistribution distribution(materials[m].distribution,
                                                  materials[m].roughness);
        for (const Vec3& wo : FurnaceDirections()) {
            const Albedo a = EstimateAlbedo(bsdf, wo, 37 + m, kFurnaceSamples);
            for (int c = 0; c < 3; ++c) {
                EXPECT_LE(a.mean[c], 1 + 4 * a.stderr_[c]) << "material " << m << " cos " << wo.z;
            }
            if (materials[m].distribution == kGgx) {
                // Visible normal sampling leaves the weight F G2 / G1(wo), never above F <= 1.
                EXPECT_LE(a.max_weight, 1 + 1e-5) << "material " << m << " cos " << wo.z;
            }
            // Nearly smooth, fully reflective: the only loss is shadowing, Lambda(wi) <=
            // alpha tan(theta) / 2 at the mirror direction, 0.01 at cos 0.05.
            if (distribution.alpha() <= MicrofacetDistribution::kMinAlpha &&
                !materials[m].conductor && std::abs(wo.z) >= 0.05f) {
                EXPECT_GT(a.mean.r, 0.99f - 4 * a.stderr_.r) << "material " << m << " cos " << wo.z;
            }
        }
    }
}

// GGX with alpha = 1 at normal incidence has a closed-form albedo: D cos is cosine-distributed,
// only normals within 45 degrees reflect above the horizon, and the weight is G2 / G1 =
// 2 cos_i / (1 + cos_i). Integrating gives 1 - ln 2.
TEST(Bsdf, GgxAlbedoMatchesClosedForm) {
    const Bsdf bsdf(Glossy(kGgx, 1.0f, Rgb(1.0f)));
    const Albedo a = EstimateAlbedo(bsdf, Vec3(0, 0, 1), 47, 200000);
    EXPECT_NEAR(a.mean.r, 1 - std::numbers::ln2, 4 * a.stderr_.r);
}

// Sample and Eval are independent routes to the albedo: cosine-weighted sampling of Eval must
// agree with importance sampling through Sample.
TEST(Bsdf, GlossyAlbedoMatchesEvalIntegral) {
    const std::vector<Material> materials = {Glossy(kGgx, 0.2f), Glossy(kGgx, 0.6f),
                                             Glossy(kBeckmann, 0.3f), Gold(kBeckmann, 0.8f),
                                             Gold(kGgx, 1.0f)};
    const Bsdf cosine_sampler(Lambert(Rgb(1.0f)));
    for (size_t m = 0; m < materials.size(); ++m) {
        const Bsdf bsdf(materials[m]);
        for (const Vec3& wo : FurnaceDirections()) {
            const Albedo sampled = EstimateAlbedo(bsdf, wo, 41 + m, kFurnaceSamples);
            const int n = 50000;
            double sum = 0, sum2 = 0;
            for (int i = 0; i < n; ++i) {
                Sampler sampler(43 + m, 0, 0, uint64_t(i));
                const auto bs = cosine_sampler.Sample(wo, 0, sampler.Get2D());
                if (!bs) continue;
                const double w = bsdf.Eval(wo, bs->wi).g * std::abs(bs->wi.z) / bs->pdf;
                sum += w;
                sum2 += w * w;
            }
            const double mean = sum / n;
            const double se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
            const double tolerance = 4 * std::hypot(se, double(sampled.stderr_.g));
            EXPECT_NEAR(sampled.mean.g, mean, tolerance) << "material " << m << " cos " << wo.z;
        }
    }
}

TEST(Bsdf, DielectricSplitsEnergyByFresnel) {
    for (float ior : {1.5f, 1.33f, 2.4f}) {
        const Bsdf bsdf(Dielectric(ior));
        EXPECT_TRUE(bsdf.IsDelta());
        for (const Vec3& wo : FurnaceDirections()) {
            const float fresnel = FrDielectric(wo.z, ior);
            const float eta_i = wo.z > 0 ? 1 : ior;  // IOR on wo's side
            const float eta_t = wo.z > 0 ? ior : 1;
            int reflected = 0;
            double energy = 0;
            for (int i = 0; i < kFurnaceSamples; ++i) {
                Sampler sampler(53, 0, 0, uint64_t(i));
                const float uc = sampler.Get1D();
                const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, sampler.Get2D());
                ASSERT_TRUE(bs);
                ASSERT_TRUE(bs->delta);
                EXPECT_TRUE(bsdf.Eval(wo, bs->wi).IsBlack());
                EXPECT_EQ(bsdf.Pdf(wo, bs->wi), 0);
                const float w = bs->f.g * std::abs(bs->wi.z) / bs->pdf;
                if (bs->wi.z * wo.z > 0) {
                    ++reflected;
                    EXPECT_EQ(bs->wi, Vec3(-wo.x, -wo.y, wo.z));
                    EXPECT_FLOAT_EQ(bs->pdf, fresnel);
                    EXPECT_NEAR(w, 1, 1e-5);
                    energy += w;
                } else {
                    EXPECT_FLOAT_EQ(bs->pdf, 1 - fresnel);
                    // Snell: same sine times IOR, azimuth turned by pi.
                    const float sin_o = std::hypot(wo.x, wo.y),
                                sin_i = std::hypot(bs->wi.x, bs->wi.y);
                    EXPECT_NEAR(eta_i * sin_o, eta_t * sin_i, 1e-5f);
                    EXPECT_NEAR(wo.x * bs->wi.y - wo.y * bs->wi.x, 0, 1e-6f);
                    EXPECT_LE(wo.x * bs->wi.x + wo.y * bs->wi.y, 0);
                    EXPECT_NEAR(Length(bs->wi), 1, 1e-5f);
                    // Radiance transport scales by (eta_i / eta_t)^2; energy is w undone by it.
                    const float etap = eta_t / eta_i;
                    EXPECT_NEAR(w * etap * etap, 1, 1e-5);
                    energy += w * etap * etap;
                }
            }
            const double frac = double(reflected) / kFurnaceSamples;
            const double sigma =
                std::sqrt(std::max(fresnel * (1.0 - fresnel), 1e-6) / kFurnaceSamples);
            EXPECT_NEAR(frac, fresnel, 4 * sigma) << "ior " << ior << " cos " << wo.z;
            EXPECT_NEAR(energy / kFurnaceSamples, 1, 1e-5);
        }
    }
}

TEST(Bsdf, DielectricTotalInternalReflection) {
    const float ior = 1.5f;
    const Bsdf bsdf(Dielectric(ior));
    const float critical_sin = 1 / ior;
    for (float sin : {critical_sin + 1e-3f, 0.8f, 0.95f, 0.999f}) {
        const Vec3 wo(sin, 0, -std::sqrt(1 - sin * sin));  // inside the glass
        for (float uc : {0.0f, 0.5f, 0.999999f}) {
            const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, {0.5f, 0.5f});
            ASSERT_TRUE(bs);
            EXPECT_EQ(bs->pdf, 1);
            EXPECT_EQ(bs->wi, Vec3(-wo.x, -wo.y, wo.z));
            EXPECT_NEAR(bs->f.r * std::abs(bs->wi.z) / bs->pdf, 1, 1e-6f);
        }
    }
}

TEST(Bsdf, IndexMatchedDielectricPassesStraightThrough) {
    const Bsdf bsdf(Dielectric(1.0f));
    for (const Vec3& wo : FurnaceDirections()) {
        // Rounding leaves a reflection probability of order 1e-15, so uc starts above it.
        for (float uc : {1e-6f, 0.5f, 0.999999f}) {
            const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, {0.5f, 0.5f});
            ASSERT_TRUE(bs);
            EXPECT_NEAR(bs->pdf, 1, 1e-6f);
            for (int i = 0; i < 3; ++i) EXPECT_NEAR(bs->wi[i], -wo[i], 1e-6f);
            EXPECT_NEAR(bs->f.r * std::abs(bs->wi.z) / bs->pdf, 1, 1e-5f);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Analytic checks.

TEST(Bsdf, LambertEvalAndPdf) {
    const Rgb rho(0.2f, 0.5f, 0.8f);
    const Bsdf bsdf(Lambert(rho));
    EXPECT_FALSE(bsdf.IsDelta());
    for (int i = 0; i < 1000; ++i) {
        Sampler sampler(61, 0, 0, uint64_t(i));
        const Vec3 wo = UniformSphere(sampler.Get2D()), wi = UniformSphere(sampler.Get2D());
        const Rgb f = bsdf.Eval(wo, wi);
        if (wo.z * wi.z > 0) {
            for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(f[c], rho[c] / float(kPi));
            EXPECT_FLOAT_EQ(bsdf.Pdf(wo, wi), std::abs(wi.z) / float(kPi));
        } else {
            EXPECT_TRUE(f.IsBlack());
            EXPECT_EQ(bsdf.Pdf(wo, wi), 0);
        }
    }
}

TEST(Microfacet, DistributionIsNormalised) {
    for (auto d : {kGgx, kBeckmann}) {
        for (float alpha : {0.01f, 0.05f, 0.2f, 0.5f, 1.0f, 2.0f}) {
            const MicrofacetDistribution distribution(d, alpha);
            // Isotropic: integrate over theta only.
            const double integral = Integrate1D(
                [&](double theta) {
                    const Vec3 wm = Spherical(theta, 0);
                    return 2 * kPi * distribution.D(wm) * std::cos(theta) * std::sin(theta);
                },
                0, kPi / 2, 2000);
            EXPECT_NEAR(integral, 1, 1e-5) << int(d) << " alpha " << alpha;
        }
    }
}

// The visible normals seen from any wo integrate to one only if Lambda is the Smith Lambda of D.
TEST(Microfacet, VisibleNormalsAreNormalised) {
    for (auto d : {kGgx, kBeckmann}) {
        for (float alpha : {0.05f, 0.2f, 0.5f, 1.0f}) {
            const MicrofacetDistribution distribution(d, alpha);
            for (double theta_o : {0.0, 30.0, 60.0, 80.0, 89.0}) {
                const Vec3 wo = Spherical(Radians(theta_o), 0.3);
                const double g1 = distribution.G1(wo);
                const double integral =
                    Integrate1D(
                        [&](double theta) {
                            return std::sin(theta) * Integrate1D(
                                                         [&](double phi) {
                                                             const Vec3 wm = Spherical(theta, phi);
                                                             return std::max(0.0f, Dot(wo, wm)) *
                                                                    double(distribution.D(wm));
                                                         },
                                                         0, 2 * kPi, 100);
                        },
                        0, kPi / 2, 100) *
                    g1 / wo.z;
                // The kink along wo.wm = 0 limits this quadrature to about 1e-5.
                EXPECT_NEAR(integral, 1, 2e-5) << int(d) << " alpha " << alpha << " " << theta_o;
            }
        }
    }
}

TEST(Microfacet, GgxLambdaMatchesClosedForm) {
    for (float alpha : {0.05f, 0.3f, 1.0f}) {
        const MicrofacetDistribution distribution(kGgx, alpha);
        for (double theta : {0.0, 0.3, 1.0, 1.5, 1.57}) {
            const Vec3 w = Spherical(theta, 0.2);
            const double tan2 = std::tan(theta) * std::tan(theta);
            const double lambda = (std::sqrt(1 + alpha * alpha * tan2) - 1) / 2;
            EXPECT_NEAR(distribution.G1(w), 1 / (1 + lambda), 1e-5) << alpha << " " << theta;
        }
    }
}

// G is height-correlated: 1 / (1 + Lambda(wo) + Lambda(wi)), not G1(wo) G1(wi).
TEST(Microfacet, ShadowingIsHeightCorrelated) {
    const auto lambda = [](double alpha, double theta) {
        const double tan2 = std::tan(theta) * std::tan(theta);
        return (std::sqrt(1 + alpha * alpha * tan2) - 1) / 2;
    };
    for (float alpha : {0.05f, 0.3f, 1.0f}) {
        const MicrofacetDistribution distribution(kGgx, alpha);
        for (double to : {0.0, 0.7, 1.4}) {
            for (double ti : {0.2, 1.0, 1.55}) {
                const double expected = 1 / (1 + lambda(alpha, to) + lambda(alpha, ti));
                EXPECT_NEAR(distribution.G(Spherical(to, 0.1), Spherical(ti, 2.5)), expected, 1e-5)
                    << alpha << " " << to << " " << ti;
            }
        }
    }
}

TEST(Microfacet, GOverCosinesIsGDividedByTheCosines) {
    for (auto d : {kGgx, kBeckmann}) {
        const MicrofacetDistribution distribution(d, 0.3f);
        for (double to : {0.0, 0.7, 1.4, 2.0}) {
            for (double ti : {0.2, 1.0, 1.55, 2.9}) {
                const Vec3 wo = Spherical(to, 0.1), wi = Spherical(ti, 2.5);
                const double expected = distribution.G(wo, wi) / std::abs(double(wo.z) * wi.z);
                EXPECT_NEAR(distribution.GOverCosines(wo, wi), expected, 1e-5 * expected)
                    << int(d) << " " << to << " " << ti;
            }
        }
    }
}

// Eval is D(wm) G(wo, wi) F(wo.wm) / (4 cos_o cos_i), assembled here from the public pieces.
TEST(Bsdf, GlossyEvalIsTorranceSparrow) {
    std::vector<Material> materials;
    for (auto d : {kGgx, kBeckmann}) {
        for (float alpha : {0.1f, 0.4f, 1.0f}) {
            materials.push_back(Glossy(d, alpha, Rgb(0.9f, 0.5f, 0.04f)));
            materials.push_back(Gold(d, alpha));
        }
    }
    for (size_t m = 0; m < materials.size(); ++m) {
        const Material& mat = materials[m];
        const Bsdf bsdf(mat);
        const MicrofacetDistribution distribution(mat.distribution, mat.roughness);
        for (int i = 0; i < 2000; ++i) {
            Sampler sampler(67, int(m), 0, uint64_t(i));
            Vec3 wo = UniformSphere(sampler.Get2D()), wi = UniformSphere(sampler.Get2D());
            wi.z = std::copysign(wi.z, wo.z);
            const Vec3 up_o(wo.x, wo.y, std::abs(wo.z)), up_i(wi.x, wi.y, std::abs(wi.z));
            const Vec3 wm = Normalize(up_o + up_i);
            const float cos_om = Dot(up_o, wm);
            const Rgb fresnel = mat.conductor ? FrComplex(cos_om, mat.eta, mat.k)
                                              : FrSchlick(mat.reflectance, cos_om);
            const double scale = double(distribution.D(wm)) * distribution.G(up_o, up_i) /
                                 (4 * double(up_o.z) * up_i.z);
            const Rgb f = bsdf.Eval(wo, wi);
            for (int c = 0; c < 3; ++c) {
                const double expected = scale * fresnel[c];
                EXPECT_NEAR(f[c], expected, 1e-4 * expected + std::numeric_limits<float>::min())
                    << "material " << m << " channel " << c;
            }
        }
    }
}

TEST(Fresnel, DielectricNormalIncidence) {
    for (float n : {1.33f, 1.5f, 2.4f}) {
        const float expected = ((n - 1) / (n + 1)) * ((n - 1) / (n + 1));
        EXPECT_NEAR(FrDielectric(1, n), expected, 1e-7f);
        EXPECT_NEAR(FrDielectric(-1, n), expected, 1e-7f);  // from inside
        EXPECT_NEAR(FrDielectric(1, 1 / n), expected, 1e-7f);
    }
    for (float cos : {-1.0f, -0.3f, 0.01f, 0.5f, 1.0f}) EXPECT_NEAR(FrDielectric(cos, 1), 0, 1e-6f);
    EXPECT_NEAR(FrDielectric(0, 1.5f), 1, 1e-6f);  // grazing
}

TEST(Fresnel, DielectricBrewsterAngle) {
    // Parallel polarisation vanishes at tan(theta) = n; the perpendicular part is
    // ((n^2 - 1) / (n^2 + 1))^2.
    for (float n : {1.33f, 1.5f, 2.4f}) {
        const float cos = 1 / std::sqrt(1 + n * n);
        const float r_perp = (n * n - 1) / (n * n + 1);
        EXPECT_NEAR(FrDielectric(cos, n), r_perp * r_perp / 2, 1e-6f) << n;
    }
}

TEST(Fresnel, TotalInternalReflection) {
    const float n = 1.5f;
    for (float sin : {1 / n + 1e-4f, 0.8f, 0.99f, 1.0f}) {
        const float cos = std::sqrt(1 - sin * sin);
        EXPECT_EQ(FrDielectric(-cos, n), 1) << sin;
        EXPECT_EQ(FrDielectric(cos, 1 / n), 1) << sin;
    }
    EXPECT_LT(FrDielectric(-std::sqrt(1 - 0.6f * 0.6f), n), 1);
}

TEST(Fresnel, ConductorWithoutAbsorptionIsDielectric) {
    for (float n : {1.5f, 2.4f, 1 / 1.5f}) {
        for (int i = 0; i <= 100; ++i) {
            const float cos = i / 100.0f;
            EXPECT_NEAR(FrComplex(cos, {n, 0}), FrDielectric(cos, n), 1e-5f)
                << "n " << n << " cos " << cos;
        }
    }
}

TEST(Fresnel, ConductorNormalIncidence) {
    for (auto [n, k] : {std::pair(0.18f, 3.42f), std::pair(1.37f, 1.77f), std::pair(2.9f, 3.1f)}) {
        const float expected = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
        EXPECT_NEAR(FrComplex(1, {n, k}), expected, 1e-6f);
        EXPECT_NEAR(FrComplex(0, {n, k}), 1, 1e-6f);
    }
}

TEST(Fresnel, SchlickEndpoints) {
    const Rgb f0(0.04f, 0.5f, 0.9f);
    EXPECT_EQ(FrSchlick(f0, 1), f0);
    EXPECT_EQ(FrSchlick(f0, 0), Rgb(1.0f));
}

// ---------------------------------------------------------------------------------------------
// Robustness: extreme roughness and directions never give NaN, Inf or negative values.

TEST(Bsdf, NeverReturnsNonFinite) {
    std::vector<Material> materials = {Lambert(Rgb(1.0f)), Mirror(Rgb(1.0f)), Dielectric(1.5f),
                                       Dielectric(1.0f)};
    for (auto d : {kGgx, kBeckmann}) {
        for (float alpha : {0.0f, 1e-6f, 1e-3f, 0.5f, 2.0f}) {
            materials.push_back(Glossy(d, alpha));
            materials.push_back(Gold(d, alpha));
        }
    }
    std::vector<Vec3> wos;
    for (float z : {0.0f, -0.0f, 1e-30f, 1e-8f, 1e-6f, 1e-4f, 0.01f, 0.5f, 1.0f}) {
        const float s = std::sqrt(1 - z * z);
        for (Vec3 w : {Vec3(s, 0, z), Vec3(0.6f * s, 0.8f * s, z)}) {
            wos.push_back(w);
            wos.push_back(Vec3(w.x, w.y, -w.z));
        }
    }
    const float one_minus = 1 - 0x1p-24f;
    const std::vector<float> us = {0.0f, 1e-7f, 0.25f, 0.5f, 0.999f, one_minus};
    for (size_t m = 0; m < materials.size(); ++m) {
        const Bsdf bsdf(materials[m]);
        for (const Vec3& wo : wos) {
            const bool tangent = wo.z == 0;
            for (float u0 : us) {
                for (float u1 : us) {
                    for (float uc : {0.0f, 0.5f, one_minus}) {
                        const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, {u0, u1});
                        if (tangent) {
                            EXPECT_FALSE(bs) << m;
                            continue;
                        }
                        if (!bs) continue;
                        EXPECT_TRUE(bs->f.IsFinite()) << m << " wo.z " << wo.z;
                        EXPECT_GE(std::min({bs->f.r, bs->f.g, bs->f.b}), 0) << m;
                        EXPECT_TRUE(std::isfinite(bs->pdf) && bs->pdf > 0) << m << " " << wo.z;
                        EXPECT_TRUE(IsFinite(bs->wi)) << m;
                        EXPECT_NEAR(Length(bs->wi), 1, 1e-5f) << m;
                        const Rgb f = bsdf.Eval(wo, bs->wi);
                        EXPECT_TRUE(f.IsFinite()) << m;
                        const float pdf = bsdf.Pdf(wo, bs->wi);
                        EXPECT_TRUE(std::isfinite(pdf) && pdf >= 0) << m;
                    }
                }
            }
            for (const Vec3& wi : wos) {
                EXPECT_TRUE(bsdf.Eval(wo, wi).IsFinite()) << m << " " << wo.z << " " << wi.z;
                const float pdf = bsdf.Pdf(wo, wi);
                EXPECT_TRUE(std::isfinite(pdf) && pdf >= 0) << m << " " << wo.z << " " << wi.z;
            }
        }
    }
}

}  // namespace
}  // namespace lf
