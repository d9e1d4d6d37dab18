// Textures read the uv set their textureInfo.texCoord names (tests/scenes/multi_uv, made by
// make_multi_uv.py): of two emissive quads whose TEXCOORD_0 lies in the red texel and
// TEXCOORD_1 in the green one, the one whose emissiveTexture reads TEXCOORD_1 shows green.
#include <gtest/gtest.h>

#include <string>

#include "lf/core/scene_loader.h"
#include "render_path.h"

namespace lf {
namespace {

TEST(MultiUv, EmissionTextureReadsTheSetItsTexCoordNames) {
    const SceneOptions options{.width = 16, .height = 16};
    const absl::StatusOr<Scene> scene =
        LoadScene(std::string(LF_TEST_SCENES) + "/multi_uv/multi_uv.gltf", options);
    ASSERT_TRUE(scene.ok()) << scene.status();
    // The camera ray's emission has full weight and nothing else is lit: each pixel is its
    // quad's texel exactly (0 and 255 decode to 0 and 1).
    const Image image = testing::RenderPath(*scene, 4).out.image;
    for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 16; ++x) {
            if (x == 7 || x == 8) continue;  // footprints across the quads' shared edge
            const Rgb expected = x < 8 ? Rgb(0, 1, 0) : Rgb(1, 0, 0);
            const Rgb got = image.Pixel(x, y);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(got[c], expected[c], 1e-6) << "pixel " << x << "," << y << " ch " << c;
            }
        }
    }
}

// The second set is kept only on meshes whose material reads it.
TEST(MultiUv, TheSecondSetIsKeptOnlyWhereATextureReadsIt) {
    const absl::StatusOr<Scene> scene =
        LoadScene(std::string(LF_TEST_SCENES) + "/multi_uv/multi_uv.gltf", SceneOptions{});
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->meshes.size(), 2u);
    EXPECT_EQ(scene->meshes[0].uvs1.size(), 4u);
    EXPECT_FLOAT_EQ(scene->meshes[0].uvs1[0].x, 0.75f);
    EXPECT_EQ(scene->materials[size_t(scene->meshes[0].material)].emission_texture.tex_coord, 1);
    EXPECT_TRUE(scene->meshes[1].uvs1.empty());
    EXPECT_EQ(scene->meshes[1].uvs.size(), 4u);
}

}  // namespace
}  // namespace lf
