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

#include "lf/core/sampler.h"
#include "lf/kernels/fresnel.h"
#include "lf/kernels/microfacet.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

Vec3 Spherical(double theta, double phi) {
    return Vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                float(std::cos(theta)));
}

double Radians(double degrees) { return degrees * kPi / 180; }

Vec3 UniformSphere(const Vec2& u) {
    const float z = 1 - 2 * u.x;
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    const float phi = 2 * std::numbers::pi_v<float> * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

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

constexpr std::array<double, 5> kGaussNodes = {-0.9061798459386640, -0.5384693101056831, 0,
                                               0.5384693101056831, 0.9061798459386640};
constexpr std::array<double, 5> kGaussWeights = {0.2369268850561891, 0.4786286704993665,
                                                 0.5688888888888889, 0.4786286704993665,
                                                 0.2369268850561891};

// Composite 5-point Gauss–Legendre over [a, b] split into n pieces.
template <typename F>
double Integrate1D(const F& f, double a, double b, int n) {
    const double h = (b - a) / n;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        const double mid = a + (i + 0.5) * h;
        for (int j = 0; j < 5; ++j) sum += kGaussWeights[j] * f(mid + 0.5 * h * kGaussNodes[j]);
    }
    return sum * 0.5 * h;
}

template <typename F>
double GaussLegendre2D(const F& f, double x0, double x1, double y0, double y1) {
    const double hx = 0.5 * (x1 - x0), hy = 0.5 * (y1 - y0);
    double sum = 0;
    for (int i = 0; i < 5; ++i) {
        for (int j = 0; j < 5; ++j) {
            sum += kGaussWeights[i] * kGaussWeights[j] *
                   f(x0 + hx * (1 + kGaussNodes[i]), y0 + hy * (1 + kGaussNodes[j]));
        }
    }
    return sum * hx * hy;
}

// Splits the rectangle in four until the quadrants agree with their parent to abs_tol plus
// rel_tol of the value; the relative part keeps float noise in f from forcing endless splits.
template <typename F>
double Adaptive2D(const F& f, double x0, double x1, double y0, double y1, double whole,
                  double abs_tol, double rel_tol, int depth) {
    const double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
    const std::array<double, 4> q = {
        GaussLegendre2D(f, x0, xm, y0, ym), GaussLegendre2D(f, xm, x1, y0, ym),
        GaussLegendre2D(f, x0, xm, ym, y1), GaussLegendre2D(f, xm, x1, ym, y1)};
    const double sum = q[0] + q[1] + q[2] + q[3];
    if (depth == 0 || std::abs(sum - whole) <= abs_tol + rel_tol * std::abs(sum)) return sum;
    const double t = abs_tol / 4;
    return Adaptive2D(f, x0, xm, y0, ym, q[0], t, rel_tol, depth - 1) +
           Adaptive2D(f, xm, x1, y0, ym, q[1], t, rel_tol, depth - 1) +
           Adaptive2D(f, x0, xm, ym, y1, q[2], t, rel_tol, depth - 1) +
           Adaptive2D(f, xm, x1, ym, y1, q[3], t, rel_tol, depth - 1);
}

// Integral of f(direction) over the solid angle theta in [t0, t1], phi in [p0, p1]. It starts
// from n x n pieces so that no lobe can hide between the first nodes: a GGX lobe of alpha 0.05
// seen at 80 degrees is under 0.02 rad wide across the plane of incidence.
template <typename F>
double IntegrateSolidAngle(const F& f, double t0, double t1, double p0, double p1, int n,
                           double abs_tol) {
    const auto g = [&](double theta, double phi) {
        return std::sin(theta) * f(Spherical(theta, phi));
    };
    const double ht = (t1 - t0) / n, hp = (p1 - p0) / n;
    double sum = 0;
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            const double a0 = t0 + i * ht, a1 = a0 + ht, b0 = p0 + j * hp, b1 = b0 + hp;
            sum += Adaptive2D(g, a0, a1, b0, b1, GaussLegendre2D(g, a0, a1, b0, b1),
                              abs_tol / (n * n), 1e-6, 12);
        }
    }
    return sum;
}

// Regularised upper incomplete gamma function Q(a, x) (Numerical Recipes' gammq).
double GammaQ(double a, double x) {
    if (x <= 0) return 1;
    const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1) {
        double term = 1 / a, sum = term;
        for (int n = 1; n < 1000 && std::abs(term) > std::abs(sum) * 1e-15; ++n) {
            term *= x / (a + n);
            sum += term;
        }
        return 1 - sum * std::exp(log_prefactor);
    }
    constexpr double kTiny = 1e-300;
    double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
    for (int i = 1; i < 1000; ++i) {
        const double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1 / d;
        const double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1) < 1e-15) break;
    }
    return std::exp(log_prefactor) * h;
}

double ChiSquarePValue(double chi2, int dof) { return GammaQ(0.5 * dof, 0.5 * chi2); }

TEST(Chi2Helper, MatchesClosedForms) {
    for (double x : {0.1, 1.0, 3.0, 10.0, 40.0}) {
        EXPECT_NEAR(ChiSquarePValue(x, 2), std::exp(-x / 2), 1e-12) << x;
        EXPECT_NEAR(ChiSquarePValue(x, 1), std::erfc(std::sqrt(x / 2)), 1e-12) << x;
    }
    // Median of chi-square with 100 degrees of freedom is about 99.334.
    EXPECT_NEAR(ChiSquarePValue(99.3341, 100), 0.5, 1e-4);
}

// ---------------------------------------------------------------------------------------------
// Chi-square goodness of fit of Sample against Pdf (after pbrt-v4's bsdfs_test and Mitsuba).

constexpr int kThetaRes = 10;  // pi / 10 per row: the horizon is a row boundary
constexpr int kPhiRes = 2 * kThetaRes;
constexpr int kChi2Samples = 1'000'000;
constexpr double kMinExpected = 5;
constexpr double kSignificance = 0.01;

struct Chi2Case {
    std::string name;
    Material material;
    Vec3 wo;
};

std::vector<Chi2Case> Chi2Cases() {
    // Normal, oblique, grazing and back-side incidence, azimuth off the bin edges.
    const std::vector<std::pair<std::string, Vec3>> wos = {
        {"Normal", Spherical(0, 0)},
        {"Oblique45", Spherical(Radians(45), 0.5)},
        {"Grazing80", Spherical(Radians(80), 2.0)},
        {"Back130", Spherical(Radians(130), 4.0)},
    };
    std::vector<Chi2Case> cases;
    for (const auto& [wo_name, wo] : wos) {
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
    const Bsdf bsdf(c.material);
    const int num_tests = int(Chi2Cases().size());

    // Observed: histogram of sampled directions; the extra last cell counts failed samples.
    constexpr int kCells = kThetaRes * kPhiRes;
    std::vector<double> observed(kCells + 1, 0.0);
    const uint64_t seed = std::hash<std::string>{}(c.name);
    for (int i = 0; i < kChi2Samples; ++i) {
        Sampler sampler(seed, 0, 0, uint64_t(i));
        const float uc = sampler.Get1D();
        const Vec2 u = sampler.Get2D();
        const std::optional<BsdfSample> bs = bsdf.Sample(c.wo, uc, u);
        if (!bs) {
            ++observed[kCells];
            continue;
        }
        ASSERT_FALSE(bs->delta);
        const double theta = std::acos(std::clamp(double(bs->wi.z), -1.0, 1.0));
        double phi = std::atan2(double(bs->wi.y), double(bs->wi.x));
        if (phi < 0) phi += 2 * kPi;
        const int ti = std::min(int(theta / kPi * kThetaRes), kThetaRes - 1);
        const int pi = std::min(int(phi / (2 * kPi) * kPhiRes), kPhiRes - 1);
        ++observed[size_t(ti * kPhiRes + pi)];
    }

    // Expected: Pdf integrated over each cell, to a small fraction of a count.
    std::vector<double> expected(kCells + 1, 0.0);
    double integral = 0;
    for (int ti = 0; ti < kThetaRes; ++ti) {
        for (int pi = 0; pi < kPhiRes; ++pi) {
            const double p =
                IntegrateSolidAngle([&](const Vec3& wi) { return double(bsdf.Pdf(c.wo, wi)); },
                                    ti * kPi / kThetaRes, (ti + 1) * kPi / kThetaRes,
                                    pi * 2 * kPi / kPhiRes, (pi + 1) * 2 * kPi / kPhiRes, 4, 1e-7);
            expected[size_t(ti * kPhiRes + pi)] = p * kChi2Samples;
            integral += p;
        }
    }
    // Samples that Sample rejects are exactly the mass Pdf does not cover.
    expected[kCells] = std::max(0.0, 1 - integral) * kChi2Samples;

    const double fail_fraction = observed[kCells] / kChi2Samples;
    EXPECT_LE(integral, 1 + 1e-4) << "Pdf integrates to more than one";
    const double fail_sigma =
        std::sqrt(std::max(fail_fraction * (1 - fail_fraction), 1.0 / kChi2Samples) / kChi2Samples);
    EXPECT_NEAR(1 - integral, fail_fraction, 5 * fail_sigma + 1e-4 /* quadrature */)
        << "missing Pdf mass differs from the fraction of failed samples";

    // Pool the cells with small expected counts, smallest first, until the pool is big enough.
    std::vector<int> order(kCells + 1);
    for (int i = 0; i <= kCells; ++i) order[size_t(i)] = i;
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return expected[size_t(a)] < expected[size_t(b)]; });
    double chi2 = 0, pooled_observed = 0, pooled_expected = 0;
    int dof = 0;
    for (int i : order) {
        const double e = expected[size_t(i)], o = observed[size_t(i)];
        if (e == 0) {
            ASSERT_LE(o, kChi2Samples * 1e-5) << "samples in cell " << i << " of zero density";
        } else if (e < kMinExpected || (pooled_expected > 0 && pooled_expected < kMinExpected)) {
            pooled_observed += o;
            pooled_expected += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            ++dof;
        }
    }
    if (pooled_expected > 0) {
        chi2 += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) /
                pooled_expected;
        ++dof;
    }
    // The counts (failures included) sum to the sample count: one constraint.
    dof -= 1;
    ASSERT_GT(dof, 0);
    const double p_value = ChiSquarePValue(chi2, dof);
    // Sidak: every case is tested at a level that keeps the family-wise rate at kSignificance.
    const double level = 1 - std::pow(1 - kSignificance, 1.0 / num_tests);
    std::printf("[chi2] %-24s integral %.6f failed %.6f chi2 %9.2f dof %3d p %.4f\n",
                c.name.c_str(), integral, fail_fraction, chi2, dof, p_value);
    EXPECT_GT(p_value, level) << "chi2 " << chi2 << " with " << dof << " dof";
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

struct Albedo {
    Rgb mean;
    Rgb stderr_;        // standard error of the mean per channel
    double max_weight;  // largest single-sample weight over channels
};

Albedo EstimateAlbedo(const Bsdf& bsdf, const Vec3& wo, uint64_t seed, int n) {
    std::array<double, 3> sum{}, sum2{};
    double max_weight = 0;
    for (int i = 0; i < n; ++i) {
        Sampler sampler(seed, 0, 0, uint64_t(i));
        const float uc = sampler.Get1D();
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, sampler.Get2D());
        if (!bs) continue;  // a failed sample carries no energy
        const Rgb w = bs->f * (std::abs(bs->wi.z) / bs->pdf);
        EXPECT_TRUE(w.IsFinite());
        for (int c = 0; c < 3; ++c) {
            sum[size_t(c)] += w[c];
            sum2[size_t(c)] += double(w[c]) * w[c];
            max_weight = std::max(max_weight, double(w[c]));
        }
    }
    Albedo a{};
    a.max_weight = max_weight;
    for (int c = 0; c < 3; ++c) {
        const double mean = sum[size_t(c)] / n;
        const double var = std::max(0.0, sum2[size_t(c)] / n - mean * mean);
        a.mean[c] = float(mean);
        a.stderr_[c] = float(std::sqrt(var / (n - 1)));
    }
    return a;
}

// Incident directions at cos theta 1 .. 0.01, front and back.
std::vector<Vec3> FurnaceDirections() {
    std::vector<Vec3> wos;
    for (float cos : {1.0f, 0.9f, 0.7f, 0.5f, 0.3f, 0.15f, 0.05f, 0.01f}) {
        const Vec3 w = Spherical(std::acos(cos), 0.7);
        wos.push_back(w);
        wos.push_back(Vec3(w.x, w.y, -w.z));
    }
    return wos;
}

constexpr int kFurnaceSamples = 20000;

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
