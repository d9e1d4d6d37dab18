// Participating media in the JSON scene format: "media", shapes' "interior" and "exterior", the
// camera's "medium", the interface material and Beer's law as a medium.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "lf/core/scene_loader.h"
#include "scene_test.h"
#include "vdb_files.h"

namespace lf {
namespace {

constexpr char kCamera[] =
    R"({"position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 40,
        "resolution": [8, 8])";
constexpr char kMaterials[] =
    R"({"lamp": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [1, 1, 1]},
        "boundary": {"type": "interface"}})";
constexpr char kLamp[] =
    R"({"type": "quad", "material": "lamp", "vertices": [[0, 0, 0], [0, 0, 1], [1, 0, 1], )"
    R"([1, 0, 0]]})";
constexpr char kFog[] =
    R"("fog": {"type": "homogeneous", "sigma_a": [0.1, 0.2, 0.3], "sigma_s": [1, 2, 3]})";

// A scene with `media` (the object's members), the lamp and `shapes`, and the camera with
// `camera_extra` keys.
std::string MediaScene(const std::string& media, const std::string& shapes = "",
                       const std::string& camera_extra = "",
                       const std::string& materials = kMaterials) {
    return std::string(R"({"camera": )") + kCamera + camera_extra + R"(}, "materials": )" +
           materials + R"(, "media": {)" + media + R"(}, "shapes": [)" + kLamp +
           (shapes.empty() ? "" : ", " + shapes) + "]}";
}

class SceneMediaTest : public testing::SceneTest {
  protected:
    // smoke.vdb: "density" 0.5 and "temperature" 3 on [0, 4)^3 with 0.25 voxels, and a vec3s
    // "velocity".
    void WriteSmoke() {
        openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create();
        velocity->setName("velocity");
        Write("smoke.vdb",
              testing::VdbBytes({testing::ConstantGrid("density", 0.5f, 4, 0.25),
                                 testing::ConstantGrid("temperature", 3, 4, 0.25), velocity}));
    }
};

TEST_F(SceneMediaTest, HomogeneousMediumKeysAndDefaults) {
    absl::StatusOr<Scene> scene = Parse(MediaScene(
        R"("murk": {"type": "homogeneous", "sigma_a": [1, 2, 3], "sigma_s": [0.5, 0, 4],
            "scale": 2, "g": -0.3, "emission": [5, 6, 7]},
           "empty": {"type": "homogeneous"})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->media.size(), 2u);
    const Medium& murk = scene->media[0];
    EXPECT_EQ(murk.name, "murk");
    EXPECT_EQ(murk.type, Medium::Type::kHomogeneous);
    // The scale multiplies the coefficients, not the emission.
    EXPECT_EQ(murk.sigma_a, Rgb(2, 4, 6));
    EXPECT_EQ(murk.sigma_s, Rgb(1, 0, 8));
    EXPECT_FLOAT_EQ(murk.g, -0.3f);
    EXPECT_EQ(murk.emission, Rgb(5, 6, 7));
    const Medium& empty = scene->media[1];
    EXPECT_TRUE(empty.sigma_a.IsBlack() && empty.sigma_s.IsBlack() && empty.emission.IsBlack());
    EXPECT_EQ(empty.g, 0);
    EXPECT_EQ(scene->camera_medium, -1);
}

TEST_F(SceneMediaTest, GridMediumReadsItsGridsWithTheTransform) {
    WriteSmoke();
    absl::StatusOr<Scene> scene = Parse(MediaScene(
        R"("smoke": {"type": "grid", "file": "smoke.vdb", "sigma_s": [1, 1, 1], "scale": 3,
            "temperature_grid": "temperature", "temperature_scale": 500,
            "emission_grid": "density", "transform": {"translate": [1, 2, 3]}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    const Medium& smoke = scene->media[0];
    EXPECT_EQ(smoke.type, Medium::Type::kGrid);
    EXPECT_EQ(smoke.sigma_s, Rgb(3, 3, 3));
    ASSERT_TRUE(smoke.density && smoke.temperature && smoke.emission_grid);
    EXPECT_EQ(smoke.density->name, "smoke.vdb#density");  // the default density_grid
    EXPECT_EQ(smoke.density->size, (std::array<int, 3>{4, 4, 4}));
    EXPECT_EQ(smoke.density->At(2, 2, 2), 0.5f);
    EXPECT_EQ(smoke.temperature->At(1, 2, 3), 3.0f);
    EXPECT_EQ(smoke.temperature_scale, 500);
    // Index (4, 0, 0) is 1 unit along x in the file (0.25 voxels), then moved by (1, 2, 3).
    const Vec3d p = smoke.density->index_to_world.Apply(Vec3d(4, 0, 0));
    EXPECT_NEAR(p.x, 2, 1e-12);
    EXPECT_NEAR(p.y, 2, 1e-12);
    EXPECT_NEAR(p.z, 3, 1e-12);
    EXPECT_NEAR(smoke.density->world_to_index.Apply(Vec3d(1, 2, 3)).x, 0, 1e-12);
}

// The .vdb counts in the content hash as a mesh file does.
TEST_F(SceneMediaTest, ContentHashCoversTheGridFile) {
    const std::string json =
        MediaScene(R"("smoke": {"type": "grid", "file": "smoke.vdb", "sigma_a": [1, 1, 1]})");
    Write("smoke.vdb", testing::VdbBytes({testing::ConstantGrid("density", 0.5f, 2)}));
    absl::StatusOr<Scene> first = Parse(json);
    Write("smoke.vdb", testing::VdbBytes({testing::ConstantGrid("density", 0.25f, 2)}));
    absl::StatusOr<Scene> second = Parse(json);
    ASSERT_TRUE(first.ok() && second.ok()) << first.status() << second.status();
    EXPECT_NE(first->content_hash, second->content_hash);
}

TEST_F(SceneMediaTest, ShapesAndTheCameraNameTheirMedia) {
    absl::StatusOr<Scene> scene = Parse(MediaScene(
        std::string(kFog) + R"(, "glass": {"type": "homogeneous", "sigma_a": [1, 1, 1]})",
        R"({"type": "sphere", "material": "boundary", "center": [0, 0, 0], "radius": 1,
            "interior": "glass", "exterior": "fog"},
           {"type": "triangle", "material": "boundary", "interior": "fog",
            "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]})",
        R"(, "medium": "fog")"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->camera_medium, 0);
    EXPECT_EQ(scene->materials[1].type, Material::Type::kInterface);
    const MediumInterface& sphere = scene->spheres[0].media;
    EXPECT_TRUE(sphere.has_interface);
    EXPECT_EQ(sphere.interior, 1);
    EXPECT_EQ(sphere.exterior, 0);
    // One side given: the other is vacuum.
    const MediumInterface& triangle = scene->meshes[1].media;
    EXPECT_TRUE(triangle.has_interface);
    EXPECT_EQ(triangle.interior, 0);
    EXPECT_EQ(triangle.exterior, -1);
    EXPECT_FALSE(scene->meshes[0].media.has_interface);  // the lamp
}

// Beer's law as a medium: a solid transmitter with an attenuation gets a homogeneous absorber
// inside, one per material; an explicit interface keeps its own media.
TEST_F(SceneMediaTest, AttenuationBecomesAnAbsorbingInterior) {
    const std::string materials =
        R"({"lamp": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [1, 1, 1]},
            "tinted": {"type": "principled", "base_color": [1, 1, 1], "transmission": 1,
                       "thickness": 0.1, "attenuation_color": [0.5, 0.25, 0],
                       "attenuation_distance": 2},
            "thin": {"type": "principled", "base_color": [1, 1, 1], "transmission": 1,
                     "attenuation_color": [0.5, 0.5, 0.5], "attenuation_distance": 2}})";
    absl::StatusOr<Scene> scene = Parse(
        MediaScene(kFog,
                   R"({"type": "sphere", "material": "tinted", "center": [0, 0, 0], "radius": 1},
           {"type": "sphere", "material": "tinted", "center": [3, 0, 0], "radius": 1},
           {"type": "sphere", "material": "tinted", "center": [6, 0, 0], "radius": 1,
            "interior": "fog"},
           {"type": "sphere", "material": "thin", "center": [9, 0, 0], "radius": 1})",
                   "", materials));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->media.size(), 2u);
    const Medium& absorber = scene->media[1];
    EXPECT_EQ(absorber.name, "tinted (volume attenuation)");
    EXPECT_EQ(absorber.type, Medium::Type::kHomogeneous);
    EXPECT_FLOAT_EQ(absorber.sigma_a.r, float(std::log(2.0) / 2));
    EXPECT_FLOAT_EQ(absorber.sigma_a.g, float(std::log(4.0) / 2));
    // Colour 0 absorbs everything, with a finite coefficient.
    EXPECT_FLOAT_EQ(absorber.sigma_a.b, float(-std::log(1e-30) / 2));
    EXPECT_TRUE(absorber.sigma_s.IsBlack());
    for (int i : {0, 1}) {
        EXPECT_TRUE(scene->spheres[size_t(i)].media.has_interface);
        EXPECT_EQ(scene->spheres[size_t(i)].media.interior, 1);
        EXPECT_EQ(scene->spheres[size_t(i)].media.exterior, -1);
    }
    EXPECT_EQ(scene->spheres[2].media.interior, 0);
    EXPECT_FALSE(scene->spheres[3].media.has_interface);  // a thin wall has no inside
    EXPECT_TRUE(scene->materials[1].HasInterior());
    EXPECT_FALSE(scene->materials[2].HasInterior());
}

TEST_F(SceneMediaTest, MediumErrorsNameTheKeyPath) {
    ExpectError(MediaScene(R"("fog": {"type": "fast"})"),
                "scene.json: media.fog.type: unknown medium type \"fast\"; expected homogeneous "
                "or grid");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "sigma_a": [1, -1, 1]})"),
                "media.fog.sigma_a[1]: must be ≥ 0");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "sigma_s": [1, 1]})"),
                "media.fog.sigma_s: expected 3 elements, got 2");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "g": 1})"),
                "media.fog.g: must be in (-1, 1), got 1");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "g": -1.5})"),
                "media.fog.g: must be in (-1, 1), got -1.5");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "scale": -2})"),
                "media.fog.scale: must be ≥ 0");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "sigma_a": [3e38, 0, 0],
                                      "scale": 10})"),
                "media.fog.scale: sigma_a or sigma_s times scale exceeds the float range");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "sigma_t": [1, 1, 1]})"),
                "media.fog: unknown key \"sigma_t\"; a homogeneous medium has type, sigma_a");
    ExpectError(MediaScene(R"("fog": {"type": "homogeneous", "file": "smoke.vdb"})"),
                "media.fog: unknown key \"file\"");
    ExpectError(MediaScene(R"("fog": [1, 2])"), "media.fog: expected an object");
}

TEST_F(SceneMediaTest, GridErrorsNameTheKeyPathAndTheGrid) {
    WriteSmoke();
    ExpectError(MediaScene(R"("smoke": {"type": "grid", "file": "nowhere.vdb"})"),
                "scene.json: media.smoke.file \"nowhere.vdb\": ", absl::StatusCode::kNotFound);
    ExpectError(MediaScene(R"("smoke": {"type": "grid"})"),
                "media.smoke: missing required key \"file\"");
    ExpectError(MediaScene(R"("smoke": {"type": "grid", "file": "smoke.vdb",
                                        "density_grid": "dens"})"),
                "media.smoke.density_grid: smoke.vdb grid \"dens\": no such grid; the file has "
                "\"density\" (float), \"temperature\" (float), \"velocity\" (vec3s)");
    ExpectError(MediaScene(R"("smoke": {"type": "grid", "file": "smoke.vdb",
                                        "temperature_grid": "velocity"})"),
                "media.smoke.temperature_grid: smoke.vdb grid \"velocity\": a vec3s grid; media "
                "read float grids only");
    Write("notvdb.vdb", "hello");
    ExpectError(MediaScene(R"("smoke": {"type": "grid", "file": "notvdb.vdb"})"),
                "media.smoke.file: notvdb.vdb: not a readable OpenVDB file");
    ExpectError(MediaScene(R"("smoke": {"type": "grid", "file": "smoke.vdb",
                                        "transform": {"scale": 0}})"),
                "media.smoke.transform: singular");
    ExpectError(MediaScene(R"("smoke": {"type": "grid", "file": "smoke.vdb", "flame": "x"})"),
                "media.smoke: unknown key \"flame\"; a grid medium has type, file");
}

TEST_F(SceneMediaTest, UnknownMediumNamesListTheMedia) {
    ExpectError(MediaScene(kFog,
                           R"({"type": "sphere", "material": "boundary", "center": [0, 0, 0],
                               "radius": 1, "exterior": "smog"})"),
                "scene.json: shapes[1].exterior: unknown medium \"smog\"; the scene's media are "
                "\"fog\"");
    ExpectError(MediaScene(kFog, "", R"(, "medium": "smog")"),
                "camera.medium: unknown medium \"smog\"; the scene's media are \"fog\"");
    ExpectError(R"({"camera": )" + std::string(kCamera) + R"(, "medium": "fog"}, "materials": )" +
                    kMaterials + R"(, "shapes": [)" + kLamp + "]}",
                "camera.medium: unknown medium \"fog\"; the scene has no \"media\"");
}

TEST_F(SceneMediaTest, InterfaceMaterialTakesNoOtherKeys) {
    ExpectError(MediaScene(kFog, "", "",
                           R"({"lamp": {"type": "lambert", "reflectance": [0, 0, 0],
                                        "emission": [1, 1, 1]},
                               "boundary": {"type": "interface", "reflectance": [1, 1, 1]}})"),
                "materials.boundary: unknown key \"reflectance\"; an interface material");
}

}  // namespace
}  // namespace lf
