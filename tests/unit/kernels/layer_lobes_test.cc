// The principled material's layers: KHR_materials_clearcoat's GGX coat and KHR_materials_sheen's
// Charlie lobe, alone (their limits, the Charlie distribution's normalisation, the sheen albedo
// table) and over every kind of base (sampling against density, white furnace).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "bsdf_albedo.h"
#include "chi_square.h"
#include "lf/core/sampler.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/sheen_lobe.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

using testing::Albedo;
using testing::EstimateAlbedo;
using testing::FurnaceDirections;
using testing::UniformSphere;

Material Layered(const Rgb& base, float roughness, float metallic, float transmission,
                 float thickness, float clearcoat, float clearcoat_roughness, const Rgb& sheen,
                 float sheen_roughness) {
    Material m;
    m.type = Material::Type::kPrincipled;
    m.reflectance = base;
    m.roughness = roughness;
    m.metallic = metallic;
    m.transmission = transmission;
    m.thickness = thickness;
    m.clearcoat = clearcoat;
    m.clearcoat_roughness = clearcoat_roughness;
    m.sheen_color = sheen;
    m.sheen_roughness = sheen_roughness;
    return m;
}

// A coat over nothing (black base, no specular layer) is the GGX dielectric of IOR 1.5 with
// Schlick's Fresnel: the glossy BSDF with F0 0.04 and alpha = r^2, on both faces.
TEST(Clearcoat, OverNothingIsTheGgxDielectricOfIor15) {
    for (float r : {0.05f, 0.3f, 0.8f}) {
        Material coat = Layered(Rgb(0.0f), 0.5f, 0, 0, 0, 1, r, Rgb(0.0f), 0);
        coat.specular = 0;
        Material glossy;
        glossy.type = Material::Type::kGlossy;
        glossy.reflectance = Rgb(0.04f);
        glossy.roughness = r * r;
        const Bsdf a(coat), b(glossy);
        int nonzero = 0;
        for (int i = 0; i < 5000; ++i) {
            Sampler sampler(131, 0, 0, uint64_t(i));
            const Vec3 wo = UniformSphere(sampler.Get2D()), wi = UniformSphere(sampler.Get2D());
            const Rgb fa = a.Eval(wo, wi), fb = b.Eval(wo, wi);
            if (!fb.IsBlack()) ++nonzero;
            EXPECT_NEAR(fa.g, fb.g, 1e-5f * fb.g + 1e-30f) << "r " << r;
        }
        EXPECT_GT(nonzero, 2000);
    }
}

// The Charlie distribution is a distribution of normals: int D(h) cos(theta_h) dh = 1. D is
// the lobe's value with the visibility factored out; with wo = wi = h the visibility has
// cos_o = cos_i = cos_h, which Value divides by.
TEST(Sheen, CharlieDistributionIsNormalised) {
    for (float r : {0.2f, 0.5f, 1.0f}) {
        const float alpha = r * r;
        constexpr int n = 2000;
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            const double cos_h = (i + 0.5) / n;  // d omega = 2 pi d cos over the azimuth
            const double sin2 = 1 - cos_h * cos_h;
            const double d = (2 + 1 / alpha) * std::pow(sin2, 0.5 / alpha) / (2 * std::numbers::pi);
            sum += d * cos_h * 2 * std::numbers::pi / n;
        }
        EXPECT_NEAR(sum, 1, 1e-3) << r;
        // And Value is that D times the visibility: at normal incidence h = n, D is 0 for a < 1.
        const Vec3 up(0, 0, 1);
        if (r < 1) {
            EXPECT_EQ(SheenLobe::Value(up, up, alpha), 0) << r;
        }
    }
}

// The albedo table between its nodes against a fine quadrature: the base beneath is scaled by
// 1 - E, so an E too low would let sheen and base reflect more than arrives.
TEST(Sheen, AlbedoTableMatchesAFineQuadrature) {
    double worst = 0;
    for (float r : {0.21f, 0.33f, 0.61f, 0.97f}) {
        for (float mu : {0.013f, 0.2f, 0.55f, 0.93f}) {
            const double fine = SheenLobe::IntegrateAlbedo(mu, r, 512);
            const double table = SheenLobe::TabulatedAlbedo(mu, r);
            worst = std::max(worst, std::abs(fine - table) / fine);
            EXPECT_NEAR(table, fine, 2e-3 + 0.03 * fine) << "r " << r << " mu " << mu;
        }
    }
    std::printf("[sheen] largest relative table error %.2e\n", worst);
}

struct LayerCase {
    std::string name;
    Material material;
};

std::vector<LayerCase> LayerCases() {
    const Rgb white(1.0f), none(0.0f);
    std::vector<LayerCase> cases;
    Material coat_only = Layered(none, 0.5f, 0, 0, 0, 1, 0.2f, none, 0);
    coat_only.specular = 0;
    cases.push_back({"CoatOnly", coat_only});
    Material sheen_only = Layered(none, 0.5f, 0, 0, 0, 0, 0, white, 0.4f);
    sheen_only.specular = 0;
    cases.push_back({"SheenOnly", sheen_only});
    // 0.04: the sharpest coat that is still a GGX lobe (alpha 1.6e-3; below sqrt(1e-3) it is a
    // mirror, the cases after the grid).
    for (float cr : {0.04f, 0.3f, 1.0f}) {
        for (float sr : {0.1f, 0.5f, 1.0f}) {
            const std::string tag =
                "_cr" + std::to_string(int(cr * 100)) + "_sr" + std::to_string(int(sr * 10));
            cases.push_back(
                {"WhitePlastic" + tag, Layered(white, 0.5f, 0, 0, 0, 1, cr, white, sr)});
            cases.push_back({"Metal" + tag, Layered(white, 0.3f, 1, 0, 0, 1, cr, white, sr)});
            cases.push_back({"ThinGlass" + tag, Layered(white, 0.1f, 0, 1, 0, 1, cr, white, sr)});
            cases.push_back({"SolidGlass" + tag, Layered(white, 0.2f, 0, 1, 1, 1, cr, white, sr)});
        }
    }
    // Mirror-smooth coats (roughness 0): a delta lobe over every kind of base.
    cases.push_back({"SmoothCoatPlastic", Layered(white, 0.5f, 0, 0, 0, 1, 0, white, 0.5f)});
    cases.push_back({"SmoothCoatMetal", Layered(white, 0.3f, 1, 0, 0, 1, 0, none, 0)});
    cases.push_back({"SmoothCoatThinGlass", Layered(white, 0.1f, 0, 1, 0, 1, 0, white, 0.5f)});
    cases.push_back({"SmoothCoatSolidGlass", Layered(white, 0, 0, 1, 1, 1, 0, none, 0)});
    return cases;
}

LayerCase Find(const std::string& name) {
    for (LayerCase& c : LayerCases()) {
        if (c.name == name) return c;
    }
    ADD_FAILURE() << name;
    return {};
}

// A coat of roughness 0 is a mirror (issue 28): delta samples in the mirror direction carrying
// the coat's Fresnel F = 0.04 + 0.96 (1 - cos)^5 over their pick probability, no value of its
// own off them (Eval is the base beneath, a black Lambertian here, times Keep = 1 - F), and,
// over a smooth base with no diffuse part or sheen, a delta BSDF.
TEST(Clearcoat, SmoothCoatIsAMirror) {
    Material coat = Layered(Rgb(0.0f), 0.5f, 0, 0, 0, 1, 0, Rgb(0.0f), 0);
    coat.specular = 0;
    const Bsdf bsdf(coat);
    for (float cos : {0.1f, 0.5f, 0.9f}) {
        const Vec3 wo(std::sqrt(1 - cos * cos), 0, cos);
        const Vec3 mirror(-wo.x, -wo.y, wo.z);
        EXPECT_EQ(bsdf.Eval(wo, mirror).g, 0) << cos;
        int deltas = 0;
        for (int i = 0; i < 256; ++i) {
            Sampler sampler(17, 0, 0, uint64_t(i));
            const float uc = sampler.Get1D();
            const std::optional<BsdfSample> s = bsdf.Sample(wo, uc, sampler.Get2D());
            if (!s || !s->delta) continue;
            ++deltas;
            EXPECT_NEAR(s->wi.x, mirror.x, 1e-6f);
            EXPECT_NEAR(s->wi.z, mirror.z, 1e-6f);
            const float fresnel = 0.04f + 0.96f * std::pow(1 - cos, 5.0f);
            EXPECT_NEAR(s->f.g * s->wi.z, fresnel, 1e-6f) << cos;
            // The delta sample's pick probability is the mass Pdf leaves out.
            EXPECT_GT(s->pdf, 0.04f) << cos;
        }
        EXPECT_GT(deltas, 10) << cos;
    }
    const Rgb white(1.0f), none(0.0f);
    EXPECT_TRUE(Bsdf(Layered(white, 0, 1, 0, 0, 1, 0, none, 0)).IsDelta());  // coated chrome
    EXPECT_FALSE(Bsdf(Layered(white, 0, 1, 0, 0, 1, 0.5f, none, 0)).IsDelta());
    EXPECT_FALSE(Bsdf(Layered(white, 0.5f, 0, 0, 0, 1, 0, none, 0)).IsDelta());
}

// White furnace: base, sheen and coat all white, never above one.
TEST(Layers, WhiteFurnaceNeverExceedsOne) {
    double highest = 0;
    std::string highest_case;
    int seed = 0;
    for (const LayerCase& c : LayerCases()) {
        const Bsdf bsdf(c.material);
        for (const Vec3& wo : FurnaceDirections()) {
            const Albedo a = EstimateAlbedo(bsdf, wo, 211 + uint64_t(seed++), 20000);
            if (a.mean.g > highest) {
                highest = a.mean.g;
                highest_case = c.name + " cos " + std::to_string(wo.z);
            }
            EXPECT_LE(a.mean.g, 1 + 4 * a.stderr_.g) << c.name << " cos " << wo.z;
        }
    }
    std::printf("[furnace] layers: highest albedo %.5f (%s)\n", highest, highest_case.c_str());
}

// The layers scatter: a coat over black reflects its Fresnel share, a sheen over black its
// albedo, so they are not silently dropped.
TEST(Layers, CoatAndSheenReflectOverABlackBase) {
    const std::vector<LayerCase> cases = LayerCases();
    const Vec3 wo(0.6f, 0, 0.8f);
    const Albedo coat = EstimateAlbedo(Bsdf(cases[0].material), wo, 5, 20000);
    EXPECT_NEAR(coat.mean.g, 0.04 + 0.96 * std::pow(0.2, 5), 4 * coat.stderr_.g + 5e-3);
    const Albedo sheen = EstimateAlbedo(Bsdf(cases[1].material), wo, 7, 20000);
    EXPECT_NEAR(sheen.mean.g, SheenLobe::IntegrateAlbedo(0.8f, 0.4f, 256),
                4 * sheen.stderr_.g + 1e-3);
}

class LayerChi2 : public ::testing::TestWithParam<LayerCase> {};

TEST_P(LayerChi2, SampleMatchesPdf) {
    const LayerCase& c = GetParam();
    const int cases = 4 * int(testing::Chi2IncidentDirections().size());
    for (const auto& [wo_name, wo] : testing::Chi2IncidentDirections()) {
        testing::ExpectSamplingMatchesPdf(Bsdf(c.material), wo, c.name + "_" + wo_name, cases);
    }
}

class SmoothCoatChi2 : public ::testing::TestWithParam<LayerCase> {};

// The rough lobes beneath a mirror coat: the coat's delta samples are the mass Pdf leaves out.
TEST_P(SmoothCoatChi2, SampleMatchesPdf) {
    const LayerCase& c = GetParam();
    const int cases = 2 * int(testing::Chi2IncidentDirections().size());
    for (const auto& [wo_name, wo] : testing::Chi2IncidentDirections()) {
        testing::ExpectSamplingMatchesPdf(Bsdf(c.material), wo, c.name + "_" + wo_name, cases,
                                          true);
    }
}

INSTANTIATE_TEST_SUITE_P(Lobes, SmoothCoatChi2,
                         ::testing::Values(Find("SmoothCoatPlastic"), Find("SmoothCoatThinGlass")),
                         [](const auto& info) { return info.param.name; });

INSTANTIATE_TEST_SUITE_P(Lobes, LayerChi2,
                         ::testing::Values(LayerCases()[0], LayerCases()[1], LayerCases()[6],
                                           LayerCases()[9]),
                         [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace lf
