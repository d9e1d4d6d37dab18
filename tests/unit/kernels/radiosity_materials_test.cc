// Radiosity takes the materials modelling tools export by their diffuse part: lambert's albedo,
// the principled base's hemispherical diffuse albedo (the path tracer's diffuse lobe, measured
// here by sampling the BSDF), black for mirrors and glass; textures averaged per patch for the
// solve and shown per texel. Alpha masks and single-sided surfaces are still refused with a
// message naming what.
#include <gtest/gtest.h>

#include <numbers>

#include "bsdf_albedo.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/principled_bsdf.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/radiosity_surfaces.h"
#include "test_scenes.h"

namespace lf {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

std::string RefusalOf(const Material& floor) {
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    scene.materials.push_back(floor);
    scene.meshes[0].material = 1;
    scene.meshes[0].name = "floor";
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    RadiosityOptions options;
    options.patches = 64;
    const auto renderer = PrepareRadiosity(**es, options);
    EXPECT_EQ(renderer.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(renderer.status().message());
}

TEST(RadiosityMaterials, MaskedAndSingleSidedAreRefused) {
    Material masked;
    masked.name = "leaf";
    masked.alpha_mode = Material::AlphaMode::kMask;
    masked.opacity = 0.2f;
    EXPECT_EQ(RefusalOf(masked),
              "radiosity: material \"leaf\" (mesh \"floor\") has an alpha mask, which radiosity "
              "does not model; render it with --method path");
    Material single;
    single.name = "card";
    single.double_sided = false;
    EXPECT_EQ(RefusalOf(single),
              "radiosity: material \"card\" (mesh \"floor\") is single-sided, which radiosity "
              "does not model; render it with --method path");
}

Material Principled(float roughness, float clearcoat, const Rgb& sheen) {
    Material m;
    m.name = "plastic";
    m.type = Material::Type::kPrincipled;
    m.reflectance = Rgb(1.0f);
    m.roughness = roughness;
    m.clearcoat = clearcoat;
    m.clearcoat_roughness = 0.3f;
    m.sheen_color = sheen;
    m.sheen_roughness = 0.5f;
    return m;
}

// The diffuse lobe's cosine-weighted albedo, measured through the path tracer's own sampling:
// the BSDF's albedo with a white base minus that with a black one (every other lobe is the same
// for both), averaged over 32 outgoing directions stratified by cosine.
float SampledDiffuseAlbedo(Material m) {
    constexpr int kDirections = 32, kSamples = 20000;
    double sum = 0;
    for (int i = 0; i < kDirections; ++i) {
        const float mu = std::sqrt((i + 0.5f) / kDirections);
        const Vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
        m.reflectance = Rgb(1.0f);
        const float white = testing::EstimateAlbedo(Bsdf(m), wo, 7, kSamples).mean.g;
        m.reflectance = Rgb(0.0f);
        const float black = testing::EstimateAlbedo(Bsdf(m), wo, 7, kSamples).mean.g;
        sum += white - black;
    }
    return float(sum / kDirections);
}

TEST(RadiosityMaterials, PrincipledDiffuseAlbedoIsThePathTracersDiffuseLobe) {
    for (const Material& m : {Principled(0.0f, 0, Rgb(0.0f)), Principled(0.3f, 0, Rgb(0.0f)),
                              Principled(0.8f, 0, Rgb(0.0f)), Principled(0.5f, 1, Rgb(0.0f)),
                              Principled(0.5f, 0, Rgb(0.8f))}) {
        const float rho = PrincipledBsdf(m, SurfaceParams::Of(m)).DiffuseAlbedo().g;
        EXPECT_NEAR(rho, SampledDiffuseAlbedo(m), 0.01)
            << "roughness " << m.roughness << " coat " << m.clearcoat << " sheen "
            << m.sheen_color.g;
        // The specular layer takes some, never most.
        EXPECT_LT(rho, 0.97f);
        EXPECT_GT(rho, 0.7f);
    }
    // Without a specular layer the base is lambert, scaled by what metal and transmission leave.
    Material m = Principled(0.5f, 0, Rgb(0.0f));
    m.specular = 0;
    m.metallic = 0.25f;
    m.transmission = 0.5f;
    m.reflectance = Rgb(0.8f, 0.4f, 0.2f);
    const Rgb rho = PrincipledBsdf(m, SurfaceParams::Of(m)).DiffuseAlbedo();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rho[c], m.reflectance[c] * 0.75f * 0.5f, 1e-6);
}

// A closed principled furnace of emission Le: every side's B = pi Le / (1 - rho), rho the
// diffuse albedo (the form factors of a closed box sum to one within 1e-5); a mirror box reflects
// nothing diffusely, so B = pi Le.
TEST(RadiosityMaterials, PrincipledAndMirrorFurnacesSolveWithTheirDiffuseAlbedo) {
    for (const bool mirror : {false, true}) {
        Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
        Material& m = scene.materials[0];
        m.type = mirror ? Material::Type::kMirror : Material::Type::kPrincipled;
        m.reflectance = Rgb(0.9f, 0.6f, 0.3f);
        m.roughness = 0.4f;
        auto es = EmbreeScene::Build(scene);
        ASSERT_TRUE(es.ok()) << es.status();
        RadiosityOptions options;
        options.patches = 96;
        options.tolerance = 1e-7;
        const auto renderer = PrepareRadiosity(**es, options);
        ASSERT_TRUE(renderer.ok()) << renderer.status();
        const Rgb rho = mirror ? Rgb() : PrincipledBsdf(m, SurfaceParams::Of(m)).DiffuseAlbedo();
        for (const Rgb& b : (*renderer)->radiosity()) {
            for (int c = 0; c < 3; ++c) {
                const float expected = kPi / (1 - rho[c]);
                EXPECT_NEAR(b[c], expected, 2e-4 * expected) << c;
            }
        }
    }
}

// A quad of corners 0 1 2 3 (triangles 0 1 2 and 0 2 3) with uvs.
TriangleMesh TexturedQuad(const std::string& name, std::vector<Vec3d> positions,
                          std::vector<Vec2> uvs) {
    TriangleMesh quad;
    quad.name = name;
    quad.is_quad = true;
    quad.positions = std::move(positions);
    quad.uvs = std::move(uvs);
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    return quad;
}

// A 2 x 2 checker (white and 20 % grey texels, linear values, nearest filtering) repeated 4 x 4
// times over a floor under a point light: the solve averages the albedo over each patch, the
// display shows each texel's albedo times the patch's irradiance, so the checker keeps its
// contrast.
TEST(RadiosityMaterials, TexturedFloorKeepsItsCheckerUnderTheIrradiance) {
    Scene scene;
    auto checker = std::make_shared<TextureImage>();
    checker->name = "checker.png";
    checker->width = checker->height = 2;
    checker->channels = 1;
    checker->texels8 = {255, 51, 51, 255};
    scene.textures.push_back(checker);
    Material floor;
    floor.name = "tiles";
    floor.type = Material::Type::kPrincipled;
    floor.specular = 0;
    floor.reflectance = Rgb(0.9f);
    floor.base_color_texture.image = 0;
    floor.base_color_texture.nearest = true;
    scene.materials.push_back(floor);
    // 4 x 4 checkers of 1 x 1.
    scene.meshes.push_back(TexturedQuad("floor", {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}},
                                        {{0, 0}, {0, 4}, {4, 4}, {4, 0}}));
    const Rgb intensity(4.0f);
    scene.point_lights.push_back({Vec3d(0, 1.5, 0), intensity});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    RadiosityOptions options;
    options.patches = 2048;
    options.display = RadiosityShading::kFlat;
    const auto renderer = PrepareRadiosity(**es, options);
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    const RadiosityDisplay& display = (*renderer)->display();
    const RadiositySurfaces surfaces(**es);
    ASSERT_TRUE(surfaces.Varies(0));
    // Texel albedos 0.9 and 0.9 * 0.2, each times the irradiance at the point.
    double bright = 0, dark = 0;
    int bright_n = 0, dark_n = 0;
    for (int i = 0; i < 40; ++i) {
        for (int j = 0; i + j < 40; ++j) {
            const double b1 = (i + 0.5) / 41, b2 = (j + 0.5) / 41;
            const Rgb rho = surfaces.At(0, 0, float(b1), float(b2)).reflectance;
            const Rgb h = display.Irradiance(0, 0, b1, b2, false);
            const Rgb l = display.Radiance(0, 0, b1, b2, false);
            ASSERT_NEAR(l.g, rho.g * h.g / kPi, 1e-6 * h.g);
            (rho.g > 0.5f ? bright : dark) += l.g / (h.g / kPi);
            ++(rho.g > 0.5f ? bright_n : dark_n);
        }
    }
    ASSERT_GT(bright_n, 0);
    ASSERT_GT(dark_n, 0);
    EXPECT_NEAR(bright / bright_n, 0.9, 1e-5);
    EXPECT_NEAR(dark / dark_n, 0.9 * 0.2, 1e-5);
    // The solve used each patch's average albedo: half the floor is bright, half dark, so the
    // area-weighted mean of the sides' reflectances is the mean of the two.
    const RadiositySides sides = surfaces.Sides((*renderer)->mesh());
    double area = 0, weighted = 0;
    for (size_t s = 0; s < sides.reflectance.size(); ++s) {
        const double a =
            (*renderer)->mesh().patches()[size_t((*renderer)->mesh().sides()[s].patch)].area;
        area += a;
        weighted += a * sides.reflectance[s].g;
    }
    EXPECT_NEAR(weighted / area, 0.9 * (1 + 0.2) / 2, 0.005);
}

// An emission texture (red and green texels, nearest) on a black quad: the solve's exitance is
// the patch mean of pi Le, and the display shows each texel's own emission.
TEST(RadiosityMaterials, EmissionTextureIsAveragedForTheSolveAndShownPerTexel) {
    Scene scene;
    auto image = std::make_shared<TextureImage>();
    image->name = "sign.png";
    image->width = 2;
    image->height = 1;
    image->channels = 3;
    image->texels8 = {255, 0, 0, 0, 255, 0};
    scene.textures.push_back(image);
    Material sign;
    sign.name = "sign";
    sign.reflectance = Rgb(0.0f);
    sign.emission = Rgb(2.0f);
    sign.emission_texture.image = 0;
    sign.emission_texture.nearest = true;
    scene.materials.push_back(sign);
    scene.meshes.push_back(TexturedQuad("sign", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                                        {{0, 0}, {1, 0}, {1, 1}, {0, 1}}));
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    RadiosityOptions options;
    options.patches = 64;
    const auto renderer = PrepareRadiosity(**es, options);
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    // Over the whole sign, half red and half green.
    const PatchMesh& mesh = (*renderer)->mesh();
    Rgb total;
    double area = 0;
    for (size_t s = 0; s < mesh.sides().size(); ++s) {
        const double a = mesh.patches()[size_t(mesh.sides()[s].patch)].area;
        total += (*renderer)->radiosity()[s] * float(a);
        area += a;
    }
    EXPECT_NEAR(total.r / area, kPi, 0.02 * kPi);
    EXPECT_NEAR(total.g / area, kPi, 0.02 * kPi);
    EXPECT_EQ(total.b, 0);
    // Triangle 0 spans (0,0), (1,0), (1,1): b1 weighs corner (1,0), b2 corner (1,1).
    const RadiosityDisplay& display = (*renderer)->display();
    const Rgb left = display.Radiance(0, 0, 0.1, 0.05, false);  // x = 0.15: the red texel
    const Rgb right = display.Radiance(0, 0, 0.5, 0.4, false);  // x = 0.9: the green texel
    EXPECT_EQ(left, Rgb(2, 0, 0));
    EXPECT_EQ(right, Rgb(0, 2, 0));
}

}  // namespace
}  // namespace lf
