#include "lf/core/gltf_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <set>
#include <sstream>

#include "gltf_files.h"
#include "image_files.h"
#include "lf/core/scene_loader.h"
#include "lf/core/texture.h"
#include "scene_log.h"
#include "test_dir.h"

namespace lf {
namespace {

using testing::GltfBuilder;
using Json = nlohmann::json;

std::ostringstream& CapturedLog() { return testing::CapturedSceneLog(); }

void ExpectNear(const Vec3d& a, const Vec3d& b, double tolerance = 1e-12) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// Each triangle's corners in order: what two meshes must agree on to be the same surface,
// whatever order their vertex arrays are in.
std::vector<std::array<Vec3d, 3>> Corners(const TriangleMesh& mesh) {
    std::vector<std::array<Vec3d, 3>> out;
    for (const auto& t : mesh.triangles) {
        out.push_back({mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]});
    }
    return out;
}

class GltfSceneTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = testing::FreshTestDir("lf_gltf_scene");
        CapturedLog().str("");
        Write("tex.png", testing::PngBytes(2, 2, 4, testing::TestTexels()));
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    void Write(const std::string& name, const std::string& bytes) {
        std::filesystem::create_directories((dir_ / name).parent_path());
        std::ofstream(dir_ / name, std::ios::binary) << bytes;
    }

    // Writes `b` as name (.gltf with name.bin beside it, or .glb) and loads it.
    absl::StatusOr<Scene> Load(const GltfBuilder& b, const std::string& name = "scene.gltf",
                               const SceneOptions& options = {}) {
        if (name.ends_with(".glb")) {
            Write(name, b.Glb());
        } else {
            Write(name, b.Gltf(std::filesystem::path(name).stem().string() + ".bin"));
            Write(std::filesystem::path(name).stem().string() + ".bin", b.bin());
        }
        return LoadScene((dir_ / name).string(), options);
    }

    // The load's error message, which the test expects to contain every one of `parts`.
    void ExpectError(const absl::StatusOr<Scene>& scene, std::initializer_list<std::string> parts) {
        ASSERT_FALSE(scene.ok());
        for (const std::string& part : parts) {
            EXPECT_NE(scene.status().message().find(part), std::string::npos)
                << "\"" << part << "\" not in: " << scene.status().message();
        }
    }

    std::filesystem::path dir_;
};

TEST_F(GltfSceneTest, LoadsTheSameGeometryCameraAndLightsAsTheEquivalentJson) {
    const absl::StatusOr<Scene> gltf = Load(testing::TexturedTestScene());
    ASSERT_TRUE(gltf.ok()) << gltf.status();
    Write("quad.obj", testing::TexturedTestQuadObj());
    const absl::StatusOr<Scene> json =
        ParseScene(testing::TexturedTestSceneJson(), "scene.json", ReadBeside(dir_.string()));
    ASSERT_TRUE(json.ok()) << json.status();

    ASSERT_EQ(gltf->meshes.size(), json->meshes.size());
    for (size_t m = 0; m < gltf->meshes.size(); ++m) {
        const TriangleMesh &gm = gltf->meshes[m], &jm = json->meshes[m];
        EXPECT_EQ(gm.material, jm.material);
        const auto a = Corners(gm), b = Corners(jm);
        ASSERT_EQ(a.size(), b.size()) << m;
        for (size_t t = 0; t < a.size(); ++t) {
            for (int c = 0; c < 3; ++c) ExpectNear(a[t][c], b[t][c]);
        }
        // Both vertex orders are the files' own, which agree here.
        ASSERT_EQ(gm.uvs.size(), jm.uvs.size()) << m;
        for (size_t v = 0; v < gm.uvs.size(); ++v) {
            EXPECT_FLOAT_EQ(gm.uvs[v].x, jm.uvs[v].x);
            EXPECT_FLOAT_EQ(gm.uvs[v].y, jm.uvs[v].y);
        }
        ASSERT_EQ(gm.normals.size(), jm.normals.size()) << m;
        for (size_t v = 0; v < gm.normals.size(); ++v) {
            ExpectNear(Vec3d(gm.normals[v]), Vec3d(jm.normals[v]), 1e-6);
        }
    }
    ASSERT_EQ(gltf->materials.size(), json->materials.size());
    for (size_t i = 0; i < json->materials.size(); ++i) {
        const Material &g = gltf->materials[i], &j = json->materials[i];
        EXPECT_EQ(g.type, j.type) << i;
        EXPECT_EQ(g.reflectance, j.reflectance) << i;
        EXPECT_EQ(g.metallic, j.metallic) << i;
        EXPECT_EQ(g.roughness, j.roughness) << i;
        EXPECT_EQ(g.double_sided, j.double_sided) << i;
        EXPECT_EQ(g.base_color_texture.valid(), j.base_color_texture.valid()) << i;
        EXPECT_EQ(g.base_color_texture.nearest, j.base_color_texture.nearest) << i;
        EXPECT_EQ(g.base_color_texture.wrap_s, j.base_color_texture.wrap_s) << i;
    }
    // One decode of tex.png, whichever format named it.
    ASSERT_EQ(gltf->textures.size(), 1u);
    ASSERT_EQ(json->textures.size(), 1u);
    EXPECT_EQ(gltf->textures[0].get(), json->textures[0].get());
    const CameraSpec &gc = gltf->camera, &jc = json->camera;
    ExpectNear(gc.position, jc.position);
    ExpectNear(Normalize(gc.look_at - gc.position), Normalize(jc.look_at - jc.position));
    ExpectNear(gc.up, jc.up);
    EXPECT_DOUBLE_EQ(gc.fov_y_deg, jc.fov_y_deg);
    EXPECT_EQ(gc.width, 1024);  // the longer side; the other from aspectRatio 1.5
    EXPECT_EQ(gc.height, 683);
    ASSERT_EQ(gltf->point_lights.size(), 1u);
    ExpectNear(gltf->point_lights[0].position, json->point_lights[0].position);
    // 6830 cd of colour (1, 0.5, 0.25) at 683 lm/W.
    EXPECT_FLOAT_EQ(gltf->point_lights[0].intensity.r, 10);
    EXPECT_FLOAT_EQ(gltf->point_lights[0].intensity.g, 5);
    EXPECT_FLOAT_EQ(gltf->point_lights[0].intensity.b, 2.5);
}

TEST_F(GltfSceneTest, ImportsShadingAttributesThroughTheNodeTransforms) {
    const absl::StatusOr<Scene> scene = Load(testing::TexturedTestScene());
    ASSERT_TRUE(scene.ok()) << scene.status();
    const TriangleMesh& quad = scene->meshes[0];
    ASSERT_EQ(quad.normals.size(), 4u);
    ASSERT_EQ(quad.uvs.size(), 4u);
    // The +z normal turned a quarter about +y faces +x; uniform scale leaves it unit.
    for (const Vec3& n : quad.normals) ExpectNear(Vec3d(n), {1, 0, 0}, 1e-6);
    EXPECT_EQ(quad.uvs[1].x, 1);
    EXPECT_EQ(quad.uvs[2].y, 0);
    EXPECT_TRUE(scene->meshes[1].normals.empty());
    EXPECT_TRUE(quad.tangents.empty());  // no normal map, no need
}

TEST_F(GltfSceneTest, TangentsAreComputedForANormalMapWhenTheFileHasNone) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["materials"][0]["normalTexture"] = {{"index", 0}};
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const TriangleMesh& quad = scene->meshes[0];
    ASSERT_EQ(quad.tangents.size(), 4u);
    // u grows along the quad's local +x, which the quarter turn about +y takes to -z; v falls
    // along local +y (up in the image), which is cross(normal, tangent): w = +1.
    for (const auto& t : quad.tangents) {
        ExpectNear(Vec3d(t[0], t[1], t[2]), {0, 0, -1}, 1e-6);
        EXPECT_EQ(t[3], 1);
    }
}

TEST_F(GltfSceneTest, NormalsUseTheInverseTransposeAndMirrorsKeepFrontFaces) {
    GltfBuilder b;
    // A 45-degree slope in xz, squashed 4x along x: its normal must tilt toward x, not z.
    const int p = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, -1}}, {{0, 1, 0}}});
    const double r = std::sqrt(0.5);
    const int n = b.AddFloats<3>(
        {{{float(r), 0, float(r)}}, {{float(r), 0, float(r)}}, {{float(r), 0, float(r)}}});
    const int slope = b.AddMesh("slope", {{"POSITION", p}, {"NORMAL", n}}, -1, -1);
    b.AddNode({{"mesh", slope}, {"scale", {0.25, 1, -1}}});
    b.AddNode({{"camera", 0}});
    b.json()["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 1}, {"znear", 1}}}}};
    b.json()["scenes"] = {{{"nodes", {0, 1}}}};
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const TriangleMesh& mesh = scene->meshes[0];
    // The surface is z' = x' * 4 after (x/4, y, -z): normal (4, 0, -1)/sqrt(17) by the
    // inverse transpose diag(4, 1, -1) of (r, 0, r).
    ExpectNear(Vec3d(mesh.normals[0]), Normalize(Vec3d(4, 0, -1)), 1e-6);
    // Scale with a negative determinant mirrors: the winding flips so the geometric front face
    // still agrees with the normals.
    const auto& t = mesh.triangles[0];
    const Vec3d front = Cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                              mesh.positions[t[2]] - mesh.positions[t[0]]);
    EXPECT_GT(Dot(front, Vec3d(mesh.normals[0])), 0);
    EXPECT_EQ(scene->camera.width, kGltfLongerSide);  // no aspectRatio: square
    EXPECT_EQ(scene->camera.height, kGltfLongerSide);
    // A primitive without material gets glTF's default material.
    const Material& m = scene->materials[size_t(mesh.material)];
    EXPECT_EQ(m.type, Material::Type::kPrincipled);
    EXPECT_EQ(m.metallic, 1);
    EXPECT_EQ(m.roughness, 1);
    EXPECT_FALSE(m.double_sided);
}

TEST_F(GltfSceneTest, MaterialsAndTexturesBecomePrincipledParametersAndSharedImages) {
    GltfBuilder b = testing::TexturedTestScene();
    Json& j = b.json();
    // A second texture of the same image with the default sampler, used by a material with every
    // extension the importer reads.
    j["textures"].push_back({{"source", 0}});
    j["materials"].push_back(
        {{"name", "glass"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {0.9, 0.8, 0.7, 0.6}},
           {"metallicFactor", 0.25},
           {"roughnessFactor", 0.3},
           {"metallicRoughnessTexture",
            {{"index", 1},
             {"extensions",
              {{"KHR_texture_transform",
                {{"offset", {0.5, 0.25}}, {"rotation", 0.1}, {"scale", {2, 3}}}}}}}}}},
         {"normalTexture", {{"index", 1}, {"scale", 0.5}}},
         {"occlusionTexture", {{"index", 1}}},
         {"emissiveFactor", {1, 0.5, 0}},
         {"emissiveTexture", {{"index", 0}}},
         {"alphaMode", "MASK"},
         {"alphaCutoff", 0.3},
         {"extensions",
          {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}},
           {"KHR_materials_transmission",
            {{"transmissionFactor", 0.75}, {"transmissionTexture", {{"index", 0}}}}},
           {"KHR_materials_ior", {{"ior", 1.33}}},
           {"KHR_materials_clearcoat",
            {{"clearcoatFactor", 0.7}, {"clearcoatRoughnessFactor", 0.2}}},
           {"KHR_materials_sheen",
            {{"sheenColorFactor", {0.9, 0.5, 0.1}}, {"sheenRoughnessFactor", 0.4}}},
           {"KHR_materials_volume",
            {{"thicknessFactor", 0.1},
             {"attenuationDistance", 2},
             {"attenuationColor", {0.5, 0.6, 0.7}}}}}}});
    j["materials"].push_back({{"name", "blend"}, {"alphaMode", "BLEND"}});
    j["meshes"][1]["primitives"][0]["material"] = 2;
    j["meshes"][0]["primitives"].push_back(j["meshes"][1]["primitives"][0]);
    j["meshes"][0]["primitives"][1]["material"] = 3;
    j["extensionsUsed"] = {"KHR_lights_punctual", "KHR_texture_transform",
                           "KHR_materials_iridescence", "KHR_materials_clearcoat",
                           "KHR_materials_sheen"};
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();

    ASSERT_EQ(scene->materials.size(), 4u);
    const Material& textured = scene->materials[0];
    EXPECT_EQ(textured.type, Material::Type::kPrincipled);
    EXPECT_EQ(textured.roughness, 0.5f);
    ASSERT_TRUE(textured.base_color_texture.valid());
    EXPECT_TRUE(textured.base_color_texture.srgb);
    EXPECT_TRUE(textured.base_color_texture.nearest);
    EXPECT_EQ(textured.base_color_texture.wrap_s, TextureRef::Wrap::kClampToEdge);
    EXPECT_EQ(textured.base_color_texture.wrap_t, TextureRef::Wrap::kClampToEdge);
    EXPECT_TRUE(textured.double_sided == false);
    EXPECT_TRUE(scene->materials[1].double_sided);

    const Material& glass = scene->materials[2];
    EXPECT_FLOAT_EQ(glass.reflectance.g, 0.8f);
    EXPECT_FLOAT_EQ(glass.opacity, 0.6f);
    EXPECT_FLOAT_EQ(glass.metallic, 0.25f);
    EXPECT_FLOAT_EQ(glass.roughness, 0.3f);
    const TextureRef& mr = glass.metallic_roughness_texture;
    EXPECT_FALSE(mr.srgb);
    EXPECT_FALSE(mr.nearest);
    EXPECT_EQ(mr.wrap_s, TextureRef::Wrap::kRepeat);
    EXPECT_FLOAT_EQ(mr.offset.x, 0.5f);
    EXPECT_FLOAT_EQ(mr.offset.y, 0.25f);
    EXPECT_FLOAT_EQ(mr.rotation, 0.1f);
    EXPECT_FLOAT_EQ(mr.scale.y, 3);
    EXPECT_FALSE(glass.normal_texture.srgb);
    EXPECT_FLOAT_EQ(glass.normal_scale, 0.5f);
    EXPECT_TRUE(glass.emission_texture.srgb);
    // Emitted radiance: emissiveFactor times emissiveStrength.
    EXPECT_FLOAT_EQ(glass.emission.r, 4);
    EXPECT_FLOAT_EQ(glass.emission.g, 2);
    EXPECT_FLOAT_EQ(glass.transmission, 0.75f);
    EXPECT_TRUE(glass.transmission_texture.valid());
    EXPECT_FALSE(glass.transmission_texture.srgb);
    EXPECT_FLOAT_EQ(glass.ior, 1.33f);
    EXPECT_FLOAT_EQ(glass.thickness, 0.1f);
    EXPECT_FLOAT_EQ(glass.attenuation_distance, 2);
    EXPECT_FLOAT_EQ(glass.attenuation_color.b, 0.7f);
    EXPECT_EQ(glass.alpha_mode, Material::AlphaMode::kMask);
    EXPECT_FLOAT_EQ(glass.alpha_cutoff, 0.3f);
    const Material& blend = scene->materials[3];
    EXPECT_EQ(blend.alpha_mode, Material::AlphaMode::kBlend);

    // One image, decoded once, shared by every ref to it, texels top row first.
    ASSERT_EQ(scene->textures.size(), 1u);
    EXPECT_EQ(textured.base_color_texture.image, mr.image);
    EXPECT_EQ(glass.emission_texture.image, mr.image);
    const TextureImage& image = *scene->textures[0];
    EXPECT_EQ(image.width, 2);
    const Rgba top_right = Texel(image, 1, 0, false);
    EXPECT_FLOAT_EQ(top_right.rgb.g, 1);
    EXPECT_FLOAT_EQ(Texel(image, 1, 1, false).a, 128 / 255.0f);

    const std::string log = CapturedLog().str();
    EXPECT_NE(log.find("occlusionTexture ignored"), std::string::npos) << log;
    EXPECT_EQ(log.find("BLEND"), std::string::npos) << log;
    EXPECT_NE(log.find("extension KHR_materials_iridescence not supported: thin-film iridescence"),
              std::string::npos)
        << log;
    EXPECT_EQ(log.find("KHR_materials_clearcoat"), std::string::npos) << log;
    EXPECT_EQ(log.find("KHR_materials_sheen"), std::string::npos) << log;
    EXPECT_FLOAT_EQ(glass.clearcoat, 0.7f);
    EXPECT_FLOAT_EQ(glass.clearcoat_roughness, 0.2f);
    EXPECT_FLOAT_EQ(glass.sheen_color.g, 0.5f);
    EXPECT_FLOAT_EQ(glass.sheen_roughness, 0.4f);
}

TEST_F(GltfSceneTest, SpotAndDirectionalLightsPointDownTheirNodesMinusZ) {
    GltfBuilder b = testing::TexturedTestScene();
    Json& j = b.json();
    j["extensions"]["KHR_lights_punctual"]["lights"].push_back(
        {{"type", "spot"},
         {"intensity", 683},
         {"range", 5},
         {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.4}}}});
    j["extensions"]["KHR_lights_punctual"]["lights"].push_back(
        {{"type", "directional"}, {"color", {0.5, 1, 1}}, {"intensity", 1366}});
    const double s = std::sqrt(0.5);  // a quarter turn about +x: -z becomes -y, straight down
    const int spot = b.AddNode({{"translation", {0, 3, 0}},
                                {"rotation", {-s, 0, 0, s}},
                                {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    const int sun = b.AddNode(
        {{"rotation", {-s, 0, 0, s}}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
    j["scenes"][0]["nodes"].push_back(spot);
    j["scenes"][0]["nodes"].push_back(sun);
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->spot_lights.size(), 1u);
    const SpotLight& light = scene->spot_lights[0];
    ExpectNear(light.position, {0, 3, 0});
    ExpectNear(light.direction, {0, -1, 0}, 1e-12);
    EXPECT_FLOAT_EQ(light.intensity.g, 1);  // 683 cd
    EXPECT_DOUBLE_EQ(light.inner_cone, 0.2);
    EXPECT_DOUBLE_EQ(light.outer_cone, 0.4);
    EXPECT_EQ(light.falloff, SpotLight::Falloff::kKhrLightsPunctual);  // as glTF viewers show it
    ASSERT_EQ(scene->directional_lights.size(), 1u);
    ExpectNear(scene->directional_lights[0].direction, {0, -1, 0}, 1e-12);
    EXPECT_FLOAT_EQ(scene->directional_lights[0].irradiance.r, 1);  // 0.5 * 1366 lx / 683
    EXPECT_FLOAT_EQ(scene->directional_lights[0].irradiance.g, 2);
    EXPECT_NE(CapturedLog().str().find("range ignored"), std::string::npos);
}

TEST_F(GltfSceneTest, GlbAndEmbeddedBuffersLoadTheSameScene) {
    const GltfBuilder b = testing::TexturedTestScene();
    const absl::StatusOr<Scene> gltf = Load(b);
    const absl::StatusOr<Scene> glb = Load(b, "scene.GLB");
    Write("embedded.gltf", b.GltfEmbedded());
    const absl::StatusOr<Scene> embedded = LoadScene((dir_ / "embedded.gltf").string());
    ASSERT_TRUE(gltf.ok()) << gltf.status();
    ASSERT_TRUE(glb.ok()) << glb.status();
    ASSERT_TRUE(embedded.ok()) << embedded.status();
    for (const Scene* other : {&*glb, &*embedded}) {
        ASSERT_EQ(other->meshes.size(), gltf->meshes.size());
        EXPECT_EQ(other->meshes[0].positions[2], gltf->meshes[0].positions[2]);
        EXPECT_EQ(other->textures.size(), 1u);
    }
    // The content hash covers the buffer and the image: another texture, another hash.
    Write("tex.png", testing::PngBytes(1, 1, 3, {1, 2, 3}));
    const absl::StatusOr<Scene> retextured = LoadScene((dir_ / "scene.gltf").string());
    ASSERT_TRUE(retextured.ok()) << retextured.status();
    EXPECT_NE(retextured->content_hash, gltf->content_hash);
}

TEST_F(GltfSceneTest, CameraOptionPicksACameraByNameAndUnknownNamesListTheCameras) {
    GltfBuilder b = testing::TexturedTestScene();
    const int side = b.AddNode({{"name", "Side"}, {"camera", 0}, {"translation", {9, 1, 0}}});
    b.json()["scenes"][0]["nodes"].push_back(side);
    const absl::StatusOr<Scene> first = Load(b);
    ASSERT_TRUE(first.ok()) << first.status();
    ExpectNear(first->camera.position, {3, 1, 6});
    const absl::StatusOr<Scene> picked = Load(b, "scene.gltf", {.camera = "Side"});
    ASSERT_TRUE(picked.ok()) << picked.status();
    ExpectNear(picked->camera.position, {9, 1, 0});
    ExpectError(Load(b, "scene.gltf", {.camera = "Top"}),
                {"scene.gltf", "no camera named \"Top\"", "\"Front\", \"Side\""});
    // --resolution overrides the glTF's.
    const absl::StatusOr<Scene> sized =
        Load(b, "scene.gltf", {.camera = "", .width = 40, .height = 30});
    ASSERT_TRUE(sized.ok()) << sized.status();
    EXPECT_EQ(sized->camera.width, 40);
    EXPECT_EQ(sized->camera.height, 30);
}

// attenuationDistance is a length in the file's world space: a JSON scene that includes the
// file at a hundredth of its size absorbs over a hundredth of the distance.
TEST_F(GltfSceneTest, AnIncludingTransformScalesTheAttenuationDistance) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["materials"][0]["extensions"]["KHR_materials_volume"] = {{"thicknessFactor", 0.1},
                                                                      {"attenuationDistance", 2}};
    const absl::StatusOr<Scene> direct = Load(b, "glass.gltf");
    ASSERT_TRUE(direct.ok()) << direct.status();
    EXPECT_FLOAT_EQ(direct->materials[0].attenuation_distance, 2);
    const absl::StatusOr<Scene> included = ParseScene(
        R"({"materials": {}, "shapes": [{"type": "gltf", "file": "glass.gltf",
            "transform": {"scale": 0.01}}]})",
        "scene.json", ReadBeside(dir_.string()));
    ASSERT_TRUE(included.ok()) << included.status();
    EXPECT_FLOAT_EQ(included->materials[0].attenuation_distance, 0.02f);
}

// A transmitting glTF solid's attenuation becomes its interior medium, as a JSON scene's does;
// a JSON "interior" on the included file puts every mesh of it between the named media.
TEST_F(GltfSceneTest, AttenuationIsAMediumAndAnIncludedFileTakesInterfaces) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["materials"][0]["extensions"]["KHR_materials_transmission"] = {
        {"transmissionFactor", 1}};
    b.json()["materials"][0]["extensions"]["KHR_materials_volume"] = {
        {"thicknessFactor", 0.1}, {"attenuationDistance", 2}, {"attenuationColor", {0.5, 1, 1}}};
    const absl::StatusOr<Scene> direct = Load(b, "glass.gltf");
    ASSERT_TRUE(direct.ok()) << direct.status();
    ASSERT_EQ(direct->media.size(), 1u);
    EXPECT_FLOAT_EQ(direct->media[0].sigma_a.r, float(std::log(2.0) / 2));
    EXPECT_EQ(direct->media[0].sigma_a.g, 0);
    EXPECT_EQ(direct->meshes[0].media.interior, 0);
    const absl::StatusOr<Scene> included = ParseScene(
        R"({"materials": {}, "media": {"fog": {"type": "homogeneous", "sigma_s": [1, 1, 1]}},
            "shapes": [{"type": "gltf", "file": "glass.gltf", "exterior": "fog"}]})",
        "scene.json", ReadBeside(dir_.string()));
    ASSERT_TRUE(included.ok()) << included.status();
    EXPECT_EQ(included->media.size(), 1u);  // the explicit interface wins over the attenuation
    for (const TriangleMesh& mesh : included->meshes) {
        EXPECT_TRUE(mesh.media.has_interface);
        EXPECT_EQ(mesh.media.interior, -1);
        EXPECT_EQ(mesh.media.exterior, 0);
    }
}

// KHR_materials_specular: the factor, the colour (unbounded above: F0 is clamped when
// rendering) and both textures are read, with no warning; a negative colour is refused.
TEST_F(GltfSceneTest, SpecularColourAndTexturesAreRead) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["materials"][0]["extensions"]["KHR_materials_specular"] = {
        {"specularFactor", 0.5},
        {"specularColorFactor", {2, 1, 0.5}},
        {"specularTexture", {{"index", 0}}},
        {"specularColorTexture", {{"index", 0}}}};
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const Material& m = scene->materials[0];
    EXPECT_EQ(m.specular, 0.5f);
    EXPECT_EQ(m.specular_color, Rgb(2, 1, 0.5f));
    EXPECT_EQ(m.specular_texture.image, m.base_color_texture.image);
    EXPECT_FALSE(m.specular_texture.srgb);
    EXPECT_EQ(m.specular_color_texture.image, m.base_color_texture.image);
    EXPECT_TRUE(m.specular_color_texture.srgb);
    EXPECT_EQ(CapturedLog().str().find("specular"), std::string::npos) << CapturedLog().str();
    b.json()["materials"][0]["extensions"]["KHR_materials_specular"]["specularColorFactor"] = {
        1, -1, 1};
    ExpectError(Load(b), {"materials[0]", "KHR_materials_specular", "specularColorFactor[1] -1"});
}

// KHR_materials_unlit: the surface shows its base colour (factor times texture) as emitted
// radiance, on both faces when double-sided, and reflects nothing; required, it still loads.
TEST_F(GltfSceneTest, UnlitMaterialsEmitTheirBaseColourAndReflectNothing) {
    GltfBuilder b = testing::TexturedTestScene();
    Json& j = b.json();
    for (Json& m : j["materials"]) {
        m["extensions"]["KHR_materials_unlit"] = Json::object();
        m["emissiveFactor"] = {0.5, 0.5, 0.5};  // ignored: unlit shows the base colour only
    }
    j["extensionsUsed"].push_back("KHR_materials_unlit");
    j["extensionsRequired"].push_back("KHR_materials_unlit");
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->materials.size(), 2u);
    const Material& textured = scene->materials[0];
    EXPECT_EQ(textured.type, Material::Type::kLambert);
    EXPECT_EQ(textured.reflectance, Rgb(0.0f));
    EXPECT_EQ(textured.emission, Rgb(1.0f));
    EXPECT_EQ(textured.emission_texture.image, textured.base_color_texture.image);
    EXPECT_TRUE(textured.emission_texture.srgb);
    EXPECT_FALSE(textured.two_sided_emission);
    const Material& red = scene->materials[1];
    EXPECT_EQ(red.type, Material::Type::kLambert);
    EXPECT_EQ(red.reflectance, Rgb(0.0f));
    EXPECT_EQ(red.emission, Rgb(0.8f, 0.1f, 0.1f));
    EXPECT_FALSE(red.emission_texture.valid());
    EXPECT_TRUE(red.two_sided_emission);
    EXPECT_TRUE(red.emission_by_vertex_color);  // COLOR_0 multiplies what it shows
    EXPECT_EQ(CapturedLog().str().find("unlit"), std::string::npos) << CapturedLog().str();
}

TEST_F(GltfSceneTest, JsonSceneIncludesAGltfWithItsCameraOrItsOwn) {
    const GltfBuilder b = testing::TexturedTestScene();
    Write("models/car.gltf", b.Gltf("car.bin"));
    Write("models/car.bin", b.bin());
    Write("models/tex.png", testing::PngBytes(2, 2, 4, testing::TestTexels()));
    const std::string shape =
        R"({"type": "gltf", "file": "models/car.gltf", "transform": {"translate": [0, 10, 0]}})";
    // No JSON camera: the glTF's, moved with the file like everything in it.
    const absl::StatusOr<Scene> included = ParseScene(
        R"({"materials": {}, "shapes": [)" + shape + "]}", "scene.json", ReadBeside(dir_.string()));
    ASSERT_TRUE(included.ok()) << included.status();
    ExpectNear(included->camera.position, {3, 11, 6});
    ExpectNear(included->point_lights[0].position, {3, 15, 0});
    ExpectNear(included->meshes[0].positions[0], {1, 10, 0});
    EXPECT_EQ(included->textures.size(), 1u);
    // A JSON camera wins, unless --camera names a glTF one.
    const std::string with_camera =
        R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y_deg": 30,
            "resolution": [64, 48]}, "materials": {}, "shapes": [)" +
        shape + "]}";
    const absl::StatusOr<Scene> own =
        ParseScene(with_camera, "scene.json", ReadBeside(dir_.string()));
    ASSERT_TRUE(own.ok()) << own.status();
    EXPECT_EQ(own->camera.width, 64);
    const absl::StatusOr<Scene> named =
        ParseScene(with_camera, "scene.json", ReadBeside(dir_.string()), {.camera = "Front"});
    ASSERT_TRUE(named.ok()) << named.status();
    ExpectNear(named->camera.position, {3, 11, 6});
    // Neither a JSON camera nor a glTF one.
    GltfBuilder no_camera = b;
    no_camera.json()["scenes"][0]["nodes"] = {2, 4};
    Write("models/car.gltf", no_camera.Gltf("car.bin"));
    const absl::StatusOr<Scene> none = ParseScene(R"({"materials": {}, "shapes": [)" + shape + "]}",
                                                  "scene.json", ReadBeside(dir_.string()));
    ExpectError(none, {"scene.json", "camera", "no included glTF has a camera"});
    const absl::StatusOr<Scene> unnamed =
        ParseScene(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y_deg": 30,
                       "resolution": [64, 48]}, "materials": {}, "shapes": [)" +
                       shape + "]}",
                   "scene.json", ReadBeside(dir_.string()), {.camera = "Front"});
    ExpectError(unnamed, {"scene.json", "--camera \"Front\": the scene has no named cameras"});
}

// Bad input: each refused with the file, the glTF object and what is wrong, nothing crashed.

TEST_F(GltfSceneTest, TruncatedGlbIsRefused) {
    const std::string glb = testing::TexturedTestScene().Glb();
    for (size_t size : {size_t(3), size_t(12), size_t(30), glb.size() / 2, glb.size() - 1}) {
        Write("cut.glb", glb.substr(0, size));
        const absl::StatusOr<Scene> scene = LoadScene((dir_ / "cut.glb").string());
        ASSERT_FALSE(scene.ok()) << size;
        EXPECT_NE(scene.status().message().find("cut.glb"), std::string::npos)
            << scene.status().message();
        if (size >= 4) {  // shorter is not recognisably a .glb at all
            EXPECT_NE(scene.status().message().find("truncated glTF binary"), std::string::npos)
                << scene.status().message();
        }
    }
}

TEST_F(GltfSceneTest, MissingBufferOrTextureFileIsNamed) {
    GltfBuilder b = testing::TexturedTestScene();
    Write("scene.gltf", b.Gltf("gone.bin"));
    ExpectError(LoadScene((dir_ / "scene.gltf").string()),
                {"scene.gltf", "buffer uri \"gone.bin\""});
    b.json()["images"][0]["uri"] = "missing.png";
    ExpectError(Load(b), {"scene.gltf", "images[0] \"checker\"", "missing.png"});
}

TEST_F(GltfSceneTest, BufferViewOrAccessorBeyondItsBufferIsRefused) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["bufferViews"][0]["byteLength"] = 1 << 20;
    ExpectError(Load(b), {"scene.gltf", "meshes[0] \"quad\".primitives[0].attributes.POSITION",
                          "bufferViews[0]", "beyond buffer 0"});
    GltfBuilder c = testing::TexturedTestScene();
    c.json()["accessors"][0]["count"] = 40;
    ExpectError(Load(c), {"accessors[0]", "40 elements", "beyond bufferViews[0]"});
}

TEST_F(GltfSceneTest, NanOrInfinityInAnAccessorIsRefused) {
    GltfBuilder b;
    const int p = b.AddFloats<3>({{{0, 0, 0}}, {{1, NAN, 0}}, {{0, 1, 0}}});
    const int inf = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{0, INFINITY, 0}}});
    b.AddMesh("bad", {{"POSITION", p}}, -1, -1);
    b.AddNode({{"mesh", 0}});
    b.json()["scenes"] = {{{"nodes", {0}}}};
    ExpectError(Load(b), {"meshes[0] \"bad\"", "POSITION", "element 1 component 1 is nan"});
    b.json()["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = inf;
    ExpectError(Load(b), {"element 2 component 1 is inf"});
}

TEST_F(GltfSceneTest, UnsupportedPrimitiveModesSparseAccessorsAndComponentTypesAreRefused) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["meshes"][1]["primitives"][0]["mode"] = 1;
    ExpectError(Load(b), {"meshes[1] \"tri\".primitives[0]", "mode 1 (LINES)", "only triangles"});

    GltfBuilder sparse = testing::TexturedTestScene();
    sparse.json()["accessors"][4]["sparse"] = {
        {"count", 1},
        {"indices", {{"bufferView", 3}, {"componentType", 5125}}},
        {"values", {{"bufferView", 4}}}};
    ExpectError(Load(sparse), {"meshes[1] \"tri\"", "accessors[4]", "sparse"});

    GltfBuilder shorts = testing::TexturedTestScene();
    const std::vector<uint16_t> values(9, 1);
    const int a = shorts.AddAccessor(values.data(), 18, GltfBuilder::kUnsignedShort, "VEC3", 3);
    shorts.json()["meshes"][1]["primitives"][0]["attributes"]["POSITION"] = a;
    ExpectError(Load(shorts), {"POSITION", "UNSIGNED_SHORT (not normalized); expected FLOAT"});
}

TEST_F(GltfSceneTest, AbsurdlyLargeImageIsRefusedNamingIt) {
    // A PNG whose header claims 100000 x 100000 texels: refused from the header.
    std::string png = testing::PngBytes(1, 1, 3, {1, 2, 3});
    for (int offset : {16, 20}) {
        png[offset] = 0, png[offset + 1] = 1, png[offset + 2] = char(0x86),
        png[offset + 3] = char(0xa0);
    }
    Write("tex.png", png);
    ExpectError(Load(testing::TexturedTestScene()), {"scene.gltf", "images[0] \"checker\""});
}

TEST_F(GltfSceneTest, RequiredUnsupportedExtensionsAndMissingCamerasAreRefused) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["extensionsRequired"] = {"KHR_lights_punctual", "KHR_texture_basisu",
                                      "EXT_meshopt_compression"};
    ExpectError(Load(b), {"extensionsRequired",
                          "does not support KHR_texture_basisu, EXT_meshopt_compression"});

    GltfBuilder none = testing::TexturedTestScene();
    none.json()["scenes"][0]["nodes"] = {2, 4};
    ExpectError(Load(none), {"scene.gltf", "no camera", "include the file from a JSON scene"});
}

TEST_F(GltfSceneTest, NodeCyclesAndBadIndicesAreRefused) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["nodes"][0]["children"].push_back(2);
    ExpectError(Load(b), {"nodes[2] \"Root\"", "not a tree"});
    GltfBuilder c = testing::TexturedTestScene();
    c.json()["meshes"][0]["primitives"][0]["material"] = 7;
    ExpectError(Load(c), {"meshes[0] \"quad\".primitives[0]", "material 7 does not exist"});
}

// Every number finite, yet the product of two nested scales of 1e200 is not: refused, rather
// than NaN vertices slipping past the coordinate check.
TEST_F(GltfSceneTest, ATransformChainThatOverflowsIsRefused) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["nodes"][2]["scale"] = {1e200, 1e200, 1e200};  // "Root"
    b.json()["nodes"][0]["scale"] = {1e200, 1e200, 1e200};  // "Quad", its child
    ExpectError(Load(b), {"nodes[0] \"Quad\"", "overflows"});
}

// Finite doubles beyond float range reached Embree as infinite rays (`Assertion ray.valid()`:
// SIGABRT in `render` and in every worker that leased the job): refused at the node, as JSON
// scenes refuse coordinates beyond ±1e15.
TEST_F(GltfSceneTest, ANodeTranslatedBeyondTheCoordinateRangeIsRefused) {
    GltfBuilder camera = testing::TexturedTestScene();
    camera.json()["nodes"][3]["translation"] = {1e308, 0, 0};
    ExpectError(Load(camera), {"nodes[3] \"Front\"", "world translation (1e+308, 0, 0)", "1e+15"});
    GltfBuilder lamp = testing::TexturedTestScene();
    lamp.json()["nodes"][4]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -2e15, 0, 1};
    ExpectError(Load(lamp), {"nodes[4] \"Lamp\"", "world translation"});
}

// A scale that keeps every node's origin in range can still throw vertices and light axes out
// of it: the scene-wide check every loader ends with names them.
TEST_F(GltfSceneTest, VerticesOrLightAxesScaledOutOfRangeAreRefused) {
    GltfBuilder mesh = testing::TexturedTestScene();
    mesh.json()["nodes"][0]["scale"] = {1e20, 1e20, 1e20};  // "Quad"
    ExpectError(Load(mesh), {"mesh \"quad[0]\"", "vertex beyond"});
    GltfBuilder sun = testing::TexturedTestScene();
    Json& j = sun.json();
    j["extensions"]["KHR_lights_punctual"]["lights"].push_back(
        {{"type", "directional"}, {"intensity", 1}});
    j["scenes"][0]["nodes"].push_back(
        sun.AddNode({{"scale", {1e308, 1e308, 1e308}},
                     {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}}));
    ExpectError(Load(sun), {"directional light 0 direction"});
}

// A node scaled flat along its axis (a hidden light) leaves a spot or sun no direction: it is
// skipped with a warning instead of lighting everything with NaN.
TEST_F(GltfSceneTest, ALightFlattenedAlongItsAxisIsSkippedWithAWarning) {
    GltfBuilder b = testing::TexturedTestScene();
    Json& j = b.json();
    j["extensions"]["KHR_lights_punctual"]["lights"].push_back(
        {{"type", "spot"}, {"intensity", 683}, {"spot", {{"outerConeAngle", 0.4}}}});
    j["scenes"][0]["nodes"].push_back(b.AddNode(
        {{"scale", {1, 1, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}}));
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_TRUE(scene->spot_lights.empty());
    EXPECT_EQ(scene->point_lights.size(), 1u);
    EXPECT_NE(CapturedLog().str().find("spot light under a transform that flattens its axis"),
              std::string::npos)
        << CapturedLog().str();
}

// glTF's orthographic camera: ymag is the film's half height, xmag / ymag its aspect; it looks
// down its node's -Z like a perspective one.
TEST_F(GltfSceneTest, OrthographicCamerasKeepTheirMagnificationAndAspect) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["cameras"][0] = {
        {"type", "orthographic"},
        {"orthographic", {{"xmag", 3}, {"ymag", 1.5}, {"znear", 0.01}, {"zfar", 10}}}};
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->camera.projection, CameraSpec::Projection::kOrthographic);
    EXPECT_DOUBLE_EQ(scene->camera.half_height, 1.5);
    EXPECT_EQ(scene->camera.width, kGltfLongerSide);
    EXPECT_EQ(scene->camera.height, kGltfLongerSide / 2);
}

// A file is refused for a camera only when that camera is the one rendered; unnamed cameras are
// picked by their order.
TEST_F(GltfSceneTest, ACameraThatIsNotRenderedNeverRefusesTheFile) {
    GltfBuilder b = testing::TexturedTestScene();
    Json& j = b.json();
    j["cameras"].push_back({{"type", "perspective"}, {"perspective", {{"yfov", 0}, {"znear", 1}}}});
    j["cameras"].push_back(
        {{"type", "orthographic"},
         {"orthographic", {{"xmag", 0}, {"ymag", 1}, {"znear", 0}, {"zfar", 1}}}});
    j["scenes"][0]["nodes"].push_back(b.AddNode({{"camera", 1}}));
    j["scenes"][0]["nodes"].push_back(b.AddNode({{"camera", 2}}));
    const absl::StatusOr<Scene> first = Load(b);
    ASSERT_TRUE(first.ok()) << first.status();
    EXPECT_EQ(first->camera.projection, CameraSpec::Projection::kPerspective);
    ExpectError(Load(b, "scene.gltf", {.camera = "1"}), {"scene.gltf", "cameras[1]", "yfov 0"});
    ExpectError(Load(b, "scene.gltf", {.camera = "2"}),
                {"cameras[2]", "xmag 0 and ymag 1 must be non-zero"});
    ExpectError(Load(b, "scene.gltf", {.camera = "3"}), {"no camera named \"3\"", "0 to 2"});
}

// Khronos' Cameras asset (tests/scenes/khronos/Cameras, CC0): one perspective and one
// orthographic camera, both unnamed.
TEST(GltfCamerasAsset, LoadsWithEitherCamera) {
    const std::string path = std::string(LF_TEST_SCENES) + "/khronos/Cameras/Cameras.gltf";
    const absl::StatusOr<Scene> perspective = LoadScene(path);
    ASSERT_TRUE(perspective.ok()) << perspective.status();
    EXPECT_EQ(perspective->camera.projection, CameraSpec::Projection::kPerspective);
    EXPECT_NEAR(perspective->camera.fov_y_deg, 0.7 * 180 / std::numbers::pi, 1e-9);
    const absl::StatusOr<Scene> ortho = LoadScene(path, {.camera = "1"});
    ASSERT_TRUE(ortho.ok()) << ortho.status();
    EXPECT_EQ(ortho->camera.projection, CameraSpec::Projection::kOrthographic);
    EXPECT_DOUBLE_EQ(ortho->camera.half_height, 1);
    ExpectNear(ortho->camera.position, Vec3d(0.5, 0.5, 3));
}

// COLOR_0 as normalized unsigned bytes (VEC3, alpha 1) or floats (VEC4) becomes the mesh's
// linear RGBA vertex colours.
TEST_F(GltfSceneTest, VertexColoursAreImportedAsLinearRgba) {
    GltfBuilder b = testing::TexturedTestScene();
    const uint8_t bytes[9] = {255, 0, 0, 0, 51, 0, 0, 0, 255};
    const int tri_colours = b.AddAccessor(bytes, sizeof bytes, 5121, "VEC3", 3);
    b.json()["accessors"][size_t(tri_colours)]["normalized"] = true;
    b.json()["meshes"][1]["primitives"][0]["attributes"]["COLOR_0"] = tri_colours;
    b.json()["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = b.AddFloats<4>(
        {{{1, 1, 1, 0.25f}}, {{0.5f, 0.5f, 0.5f, 1}}, {{0, 0, 0, 1}}, {{1, 0, 1, 0.5f}}});
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const TriangleMesh* quad = nullptr;
    const TriangleMesh* tri = nullptr;
    for (const TriangleMesh& m : scene->meshes) (m.name.starts_with("quad") ? quad : tri) = &m;
    ASSERT_TRUE(quad && tri);
    ASSERT_EQ(tri->colors.size(), 3u);
    EXPECT_EQ(tri->colors[0], (std::array<float, 4>{1, 0, 0, 1}));
    EXPECT_EQ(tri->colors[1], (std::array<float, 4>{0, 0.2f, 0, 1}));
    ASSERT_EQ(quad->colors.size(), 4u);
    EXPECT_EQ(quad->colors[3], (std::array<float, 4>{1, 0, 1, 0.5f}));

    GltfBuilder bad = testing::TexturedTestScene();
    bad.json()["meshes"][1]["primitives"][0]["attributes"]["COLOR_0"] =
        bad.AddFloats<2>({{{1, 1}}, {{1, 1}}, {{1, 1}}});
    ExpectError(Load(bad), {"COLOR_0", "2 components per element, expected 3 or 4"});
}

// Khronos' VertexColorTest (tests/scenes/khronos, CC-BY 4.0, Analytical Graphics): its test
// row's checks carry red, green and blue vertex colours that zero the fail marks' channels.
TEST(GltfVertexColorAsset, TheTestRowGetsItsVertexColours) {
    const std::string path =
        std::string(LF_TEST_SCENES) + "/khronos/VertexColorTest/VertexColorTest.gltf";
    CapturedLog().str("");
    const absl::StatusOr<Scene> scene = LoadScene(path, {.camera = "auto"});
    ASSERT_TRUE(scene.ok()) << scene.status();
    size_t coloured = 0, pure[3] = {0, 0, 0};
    for (const TriangleMesh& m : scene->meshes) {
        if (m.colors.empty()) continue;
        coloured += m.colors.size();
        for (const auto& c : m.colors) {
            for (int k = 0; k < 3; ++k) {
                pure[k] +=
                    c[size_t(k)] == 1 && c[size_t((k + 1) % 3)] == 0 && c[size_t((k + 2) % 3)] == 0;
            }
        }
    }
    EXPECT_GT(coloured, 0u);
    for (const size_t n : pure) EXPECT_GT(n, 0u);
    EXPECT_EQ(CapturedLog().str().find("COLOR_0"), std::string::npos) << CapturedLog().str();
}

// KHR_draco_mesh_compression (tests/scenes/draco, made by make_draco_twins.py): a UV sphere
// as plain glTF and compressed by draco_encoder, edgebreaker (.gltf) and sequential (.glb).
std::string DracoScene(const std::string& name) {
    return std::string(LF_TEST_SCENES) + "/draco/" + name;
}

std::string FileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Each Draco triangle has a twin triangle (the encoder reorders faces and may start a face at
// another corner) whose corners agree within the quantisation: positions at 14 bits over the
// sphere's extent 2 round by at most 2/(2^14-1)/2 = 6.1e-5 per component, uvs at 12 bits over 1
// by 1.2e-4; normals at 10 bits of octahedral coordinates (spacing 2/1022) move by at most
// about one spacing, 2.0e-3, per component. Each bound is given twice its size.
void ExpectDracoTwin(const TriangleMesh& draco, const TriangleMesh& plain) {
    ASSERT_EQ(draco.triangles.size(), plain.triangles.size());
    ASSERT_EQ(draco.normals.size(), draco.positions.size());
    ASSERT_EQ(draco.uvs.size(), draco.positions.size());
    constexpr double kPosition = 2 * 6.1e-5, kUv = 2 * 1.2e-4, kNormal = 2 * 2.0e-3;
    const auto close = [&](uint32_t a, uint32_t b) {
        for (int k = 0; k < 3; ++k) {
            if (std::abs(draco.positions[a][k] - plain.positions[b][k]) > kPosition) return false;
            if (std::abs(draco.normals[a][k] - plain.normals[b][k]) > kNormal) return false;
        }
        return std::abs(draco.uvs[a].x - plain.uvs[b].x) <= kUv &&
               std::abs(draco.uvs[a].y - plain.uvs[b].y) <= kUv;
    };
    std::vector<bool> used(plain.triangles.size(), false);
    for (const auto& t : draco.triangles) {
        bool found = false;
        for (size_t j = 0; j < plain.triangles.size() && !found; ++j) {
            const auto& u = plain.triangles[j];
            for (int r = 0; r < 3 && !found && !used[j]; ++r) {
                found = close(t[0], u[size_t(r)]) && close(t[1], u[size_t((r + 1) % 3)]) &&
                        close(t[2], u[size_t((r + 2) % 3)]);
                if (found) used[j] = true;
            }
        }
        EXPECT_TRUE(found) << "no twin for the triangle at " << draco.positions[t[0]].x << " "
                           << draco.positions[t[0]].y << " " << draco.positions[t[0]].z;
    }
}

TEST(GltfDraco, EdgebreakerAndSequentialFilesEqualTheirUncompressedTwin) {
    CapturedLog().str("");
    const absl::StatusOr<Scene> plain = LoadScene(DracoScene("sphere.gltf"));
    ASSERT_TRUE(plain.ok()) << plain.status();
    ASSERT_EQ(plain->meshes.size(), 1u);
    EXPECT_EQ(plain->meshes[0].triangles.size(), 288u);
    for (const char* name : {"sphere_draco.gltf", "sphere_draco_sequential.glb"}) {
        SCOPED_TRACE(name);
        const absl::StatusOr<Scene> draco = LoadScene(DracoScene(name));
        ASSERT_TRUE(draco.ok()) << draco.status();
        ASSERT_EQ(draco->meshes.size(), 1u);
        ExpectDracoTwin(draco->meshes[0], plain->meshes[0]);
        EXPECT_EQ(draco->meshes[0].material, 0);
        EXPECT_EQ(draco->textures.size(), plain->textures.size());
    }
    EXPECT_EQ(CapturedLog().str().find("KHR_draco"), std::string::npos) << CapturedLog().str();
}

TEST_F(GltfSceneTest, CorruptOrInconsistentDracoPrimitivesAreRefusedNamingThem) {
    const std::string stream = FileBytes(DracoScene("sphere_draco.bin"));
    const Json gltf = Json::parse(FileBytes(DracoScene("sphere_draco.gltf")));
    Write("checker.png", FileBytes(DracoScene("checker.png")));
    const auto load = [&](const Json& j, const std::string& bin) {
        Write("d.gltf", j.dump());
        Write("sphere_draco.bin", bin);
        return LoadScene((dir_ / "d.gltf").string());
    };
    ASSERT_TRUE(load(gltf, stream).ok());
    const std::string at =
        "meshes[0] \"sphere\".primitives[0].extensions.KHR_draco_mesh_compression";

    // The bitstream cut in half, or its middle overwritten.
    Json half = gltf;
    half["bufferViews"][0]["byteLength"] = stream.size() / 2;
    half["buffers"][0]["byteLength"] = stream.size() / 2;
    ExpectError(load(half, stream.substr(0, stream.size() / 2)),
                {"d.gltf", at, "cannot be decoded"});
    std::string garbled = stream;
    for (size_t i = 20; i < garbled.size(); i += 3) garbled[i] = char(0xff);
    ExpectError(load(gltf, garbled), {"d.gltf", at});
    std::string not_draco = stream;
    not_draco[0] = 'X';
    ExpectError(load(gltf, not_draco), {at, "is not a Draco triangle mesh"});

    // An attribute id the bitstream lacks, or a semantic the primitive lacks.
    Json missing = gltf;
    missing["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["attributes"]
           ["NORMAL"] = 7;
    ExpectError(load(missing, stream),
                {at + ".attributes.NORMAL", "attribute id 7 is not in the bitstream"});
    Json extra = gltf;
    extra["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["attributes"]
         ["TEXCOORD_1"] = 1;
    ExpectError(load(extra, stream),
                {at + ".attributes.TEXCOORD_1", "not among the primitive's attributes"});

    // Counts that differ from the accessors': the faces the header declares, the points it
    // decodes to, and an attribute's.
    Json faces = gltf;
    faces["accessors"][3]["count"] = 3 * 287;
    ExpectError(load(faces, stream),
                {at, "the bitstream declares 288 faces", "the accessors say 287 faces"});
    Json points = gltf;
    for (int a : {0, 1, 2}) points["accessors"][a]["count"] = 184;
    ExpectError(load(points, stream), {at, "decoded 288 faces and 185 points", "184 points"});
    Json uvs = gltf;
    uvs["accessors"][2]["count"] = 184;
    ExpectError(load(uvs, stream),
                {at + ".attributes.TEXCOORD_0", "184 elements; the bitstream has 185 points"});
    Json components = gltf;
    components["accessors"][2]["type"] = "VEC3";
    ExpectError(load(components, stream),
                {at + ".attributes.TEXCOORD_0", "has 2 components; accessors[2] has 3"});

    // Absurd sizes are refused before anything is decoded.
    Json huge = gltf;
    huge["accessors"][3]["count"] = 3 * (size_t(1) << 27);
    ExpectError(load(huge, stream), {at, "more than lightfarm decodes"});
    Json no_indices = gltf;
    no_indices["meshes"][0]["primitives"][0].erase("indices");
    ExpectError(load(no_indices, stream),
                {"meshes[0] \"sphere\".primitives[0]", "has no indices accessor"});
}

// A loss many objects share is one warning with a count, and a glTF rendered directly names its
// file once in it (the log line's prefix), not once per material.
// texCoord 0 and 1 choose the uv set (KHR_texture_transform's texCoord overrides it); a
// primitive without the TEXCOORD_1 its material reads, and TEXCOORD_2 and beyond, warn.
TEST_F(GltfSceneTest, TexCoordPicksTheUvSetAndUnreadSetsWarn) {
    GltfBuilder b = testing::TexturedTestScene();
    Json& pbr = b.json()["materials"][0]["pbrMetallicRoughness"];
    pbr["baseColorTexture"]["texCoord"] = 1;
    pbr["metallicRoughnessTexture"] = {{"index", 0}, {"texCoord", 2}};
    b.json()["materials"][0]["emissiveFactor"] = {1, 1, 1};
    b.json()["materials"][0]["emissiveTexture"] = {
        {"index", 0}, {"extensions", {{"KHR_texture_transform", {{"texCoord", 1}}}}}};
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const Material& m = scene->materials[0];
    EXPECT_EQ(m.base_color_texture.tex_coord, 1);
    EXPECT_EQ(m.metallic_roughness_texture.tex_coord, 0);
    EXPECT_EQ(m.emission_texture.tex_coord, 1);
    EXPECT_TRUE(scene->meshes[0].uvs1.empty());
    const std::string log = CapturedLog().str();
    EXPECT_NE(log.find("material reads TEXCOORD_1 the primitive lacks (uv (0, 0) used) in 1 "
                       "primitive: meshes[0]"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("metallicRoughnessTexture: uses TEXCOORD_2"), std::string::npos) << log;
}

// A negative texCoord would index the uv sets from before their start: refused, naming it.
TEST_F(GltfSceneTest, ANegativeTexCoordIsRefusedNamingTheTexture) {
    GltfBuilder b = testing::TexturedTestScene();
    b.json()["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = -1;
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_FALSE(scene.ok());
    EXPECT_NE(std::string(scene.status().message()).find("texCoord -1 is negative"),
              std::string::npos)
        << scene.status();
}

TEST_F(GltfSceneTest, WarningsComeOncePerKindWithACountNamingTheFileOnce) {
    GltfBuilder b = testing::TexturedTestScene();
    for (Json& m : b.json()["materials"]) m["occlusionTexture"] = {{"index", 0}};
    const size_t materials = b.json()["materials"].size();
    ASSERT_GE(materials, 2u);
    const absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    const std::string log = CapturedLog().str();
    const std::string kind = "occlusionTexture ignored";
    const size_t at = log.find(kind);
    ASSERT_NE(at, std::string::npos) << log;
    EXPECT_EQ(log.find(kind, at + 1), std::string::npos) << log;
    const size_t begin = log.rfind('\n', at) + 1, end = log.find('\n', at);
    const std::string line = log.substr(begin, end - begin);
    EXPECT_NE(line.find(absl::StrCat("in ", materials, " materials: materials[0]")),
              std::string::npos)
        << line;
    EXPECT_EQ(line.find("scene.gltf"), line.rfind("scene.gltf")) << line;
}

}  // namespace
}  // namespace lf
