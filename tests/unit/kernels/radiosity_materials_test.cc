// Radiosity models lambert materials with one albedo and two sides per patch, lit by emitters
// and point lights: scenes with principled materials, textures, alpha masks, single-sided
// surfaces, spot or directional lights are refused with a message naming what, never rendered
// wrongly or crashed on.
#include <gtest/gtest.h>

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiosity.h"
#include "test_scenes.h"

namespace lf {
namespace {

std::string RefusalOf(const Material& floor) {
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    scene.materials.push_back(floor);
    scene.meshes[0].material = 1;
    scene.meshes[0].name = "floor";
    scene.textures.push_back(std::make_shared<TextureImage>());
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    RadiosityOptions options;
    options.patches = 64;
    const auto renderer = PrepareRadiosity(**es, options);
    EXPECT_EQ(renderer.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(renderer.status().message());
}

TEST(RadiosityMaterials, PrincipledIsRefused) {
    Material m;
    m.name = "plastic";
    m.type = Material::Type::kPrincipled;
    EXPECT_EQ(RefusalOf(m),
              "radiosity: material \"plastic\" (mesh \"floor\") is principled; radiosity models "
              "lambert only; render it with --method path");
}

TEST(RadiosityMaterials, TexturedMaskedAndSingleSidedLambertAreRefused) {
    Material textured;
    textured.name = "wood";
    textured.base_color_texture.image = 0;
    EXPECT_EQ(RefusalOf(textured),
              "radiosity: material \"wood\" (mesh \"floor\") has a texture (base_color_texture "
              "\"\"), which radiosity does not model; render it with --method path");
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

TEST(RadiosityMaterials, SpotAndDirectionalLightsAreRefused) {
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    scene.directional_lights.push_back({Vec3d(0, -1, 0), Rgb(1)});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    RadiosityOptions options;
    options.patches = 64;
    const auto renderer = PrepareRadiosity(**es, options);
    EXPECT_EQ(renderer.status().message(),
              "radiosity: the scene has spot or directional lights, which radiosity does not "
              "model; render it with --method path");
}

}  // namespace
}  // namespace lf
