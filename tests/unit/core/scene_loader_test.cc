#include "lf/core/scene_loader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <tuple>
#include <utility>

#include "gltf_files.h"
#include "image_files.h"
#include "lf/core/blackbody.h"
#include "lf/core/image_io.h"
#include "scene_log.h"
#include "scene_test.h"
#include "test_dir.h"

namespace lf {
namespace {

std::ostringstream& CapturedLog() { return testing::CapturedSceneLog(); }

size_t Count(const std::string& text, const std::string& part) {
    size_t n = 0;
    for (size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
    return n;
}

Vec3d FrontNormal(const TriangleMesh& mesh, size_t triangle) {
    const auto& t = mesh.triangles[triangle];
    const Vec3d& v0 = mesh.positions[t[0]];
    return Normalize(Cross(mesh.positions[t[1]] - v0, mesh.positions[t[2]] - v0));
}

void ExpectNear(const Vec3d& a, const Vec3d& b) {
    EXPECT_NEAR(a.x, b.x, 1e-12);
    EXPECT_NEAR(a.y, b.y, 1e-12);
    EXPECT_NEAR(a.z, b.z, 1e-12);
}

// Relative: float arithmetic in the loader (a division by a luminance, by 683).
void ExpectRgbNear(const Rgb& a, const Rgb& b, double relative = 1e-6) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], relative * b.MaxComponent()) << "ch " << c;
}

constexpr char kCamera[] =
    R"({"position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 40,
        "resolution": [32, 24]})";
constexpr char kMaterials[] =
    R"({"white": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]},
        "lamp": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [1, 2, 3]}})";
constexpr char kQuad[] =
    R"({"type": "quad", "material": "lamp", "vertices": [[0, 0, 0], [0, 0, 1], [1, 0, 1], )"
    R"([1, 0, 0]]})";

std::string SceneJson(const std::string& shapes, const std::string& materials = kMaterials,
                      const std::string& camera = kCamera, const std::string& extra = "") {
    return R"({"camera": )" + camera + R"(, "materials": )" + materials + R"(, "shapes": [)" +
           shapes + "]" + extra + "}";
}

// A scene whose material "m" is `material` (and "lamp" emits, so the scene has light).
std::string WithMaterial(const std::string& material) {
    return SceneJson(kQuad, R"({"lamp": {"type": "lambert", "reflectance": [0, 0, 0], )"
                            R"("emission": [1, 1, 1]}, "m": )" +
                                material + "}");
}

// A scene with `lights`, the JSON array's elements.
std::string WithLights(const std::string& lights) {
    return SceneJson(kQuad, kMaterials, kCamera, R"(, "lights": [)" + lights + "]");
}

class SceneLoaderTest : public testing::SceneTest {
  protected:
    void SetUp() override {
        SceneTest::SetUp();
        CapturedLog().str("");
    }
};

TEST_F(SceneLoaderTest, CornellBox) {
    absl::StatusOr<Scene> scene = LoadScene(LF_TEST_SCENES "/cornell_box.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->source, LF_TEST_SCENES "/cornell_box.json");
    EXPECT_EQ(scene->camera.width, 256);
    EXPECT_EQ(scene->camera.height, 256);
    EXPECT_DOUBLE_EQ(scene->camera.fov_y_deg, 39.3077);
    ASSERT_EQ(scene->materials.size(), 4u);
    EXPECT_EQ(scene->materials[0].name, "white");  // file order
    EXPECT_EQ(scene->materials[3].name, "light");
    EXPECT_EQ(scene->materials[3].emission, Rgb(17, 12, 4));
    ASSERT_EQ(scene->meshes.size(), 16u);
    for (const TriangleMesh& mesh : scene->meshes) {
        EXPECT_TRUE(mesh.is_quad) << mesh.name;
        EXPECT_EQ(mesh.triangles.size(), 2u) << mesh.name;
    }
    EXPECT_EQ(scene->meshes[5].name, "light");
    EXPECT_EQ(scene->meshes[5].material, 3);
    // The light faces down into the box.
    ExpectNear(FrontNormal(scene->meshes[5], 0), {0, -1, 0});
    EXPECT_TRUE(scene->spheres.empty());
    EXPECT_TRUE(scene->point_lights.empty());
    EXPECT_EQ(scene->dropped_degenerate, 0);
    EXPECT_EQ(scene->content_hash.size(), 32u);
    EXPECT_TRUE(CapturedLog().str().empty()) << CapturedLog().str();
}

TEST_F(SceneLoaderTest, QuadWindingAndFrontNormal) {
    absl::StatusOr<Scene> scene = Parse(SceneJson(kQuad));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->meshes.size(), 1u);
    const TriangleMesh& quad = scene->meshes[0];
    EXPECT_EQ(quad.name, "shapes[0]");
    EXPECT_EQ(quad.material, 1);
    EXPECT_TRUE(quad.is_quad);
    EXPECT_EQ(quad.positions, (std::vector<Vec3d>{{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}));
    EXPECT_EQ(quad.triangles, (std::vector<std::array<uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}}));
    ExpectNear(FrontNormal(quad, 0), {0, 1, 0});
    ExpectNear(FrontNormal(quad, 1), {0, 1, 0});
}

TEST_F(SceneLoaderTest, TriangleSphereAndPointLights) {
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        R"({"type": "triangle", "name": "tri", "material": "white",
            "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]},
           {"type": "sphere", "material": "lamp", "center": [1, 2, 3], "radius": 0.5})",
        kMaterials, kCamera,
        R"(, "lights": [{"type": "point", "position": [0, 1, 0], "power": [4, 8, 12]},
                        {"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}])"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->meshes.size(), 1u);
    EXPECT_EQ(scene->meshes[0].name, "tri");
    EXPECT_FALSE(scene->meshes[0].is_quad);
    ExpectNear(FrontNormal(scene->meshes[0], 0), {0, 0, 1});
    ASSERT_EQ(scene->spheres.size(), 1u);
    EXPECT_EQ(scene->spheres[0].center, Vec3d(1, 2, 3));
    EXPECT_EQ(scene->spheres[0].radius, 0.5);
    EXPECT_EQ(scene->spheres[0].material, 1);
    ASSERT_EQ(scene->point_lights.size(), 2u);
    EXPECT_EQ(scene->point_lights[0].position, Vec3d(0, 1, 0));
    const float four_pi = float(4 * std::numbers::pi);
    EXPECT_FLOAT_EQ(scene->point_lights[0].intensity.r, 4 / four_pi);
    EXPECT_FLOAT_EQ(scene->point_lights[0].intensity.b, 12 / four_pi);
    EXPECT_EQ(scene->point_lights[1].intensity, Rgb(1));
}

TEST_F(SceneLoaderTest, MaterialTypes) {
    absl::StatusOr<Scene> scene = Parse(
        SceneJson(kQuad,
                  R"({"lamp": {"type": "mirror", "reflectance": [1, 1, 1], "emission": [1, 1, 1]},
            "plastic": {"type": "glossy", "distribution": "beckmann", "roughness": 0.3,
                        "reflectance": [0.04, 0.04, 0.04]},
            "gold": {"type": "glossy", "roughness": 0.1, "eta": [0.18, 0.42, 1.37],
                     "k": [3.42, 2.35, 1.77]},
            "glass": {"type": "dielectric", "ior": 1.5}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    const std::vector<Material>& m = scene->materials;
    ASSERT_EQ(m.size(), 4u);
    EXPECT_EQ(m[0].type, Material::Type::kMirror);
    EXPECT_EQ(m[0].reflectance, Rgb(1));
    EXPECT_TRUE(m[0].IsEmissive());
    EXPECT_EQ(m[1].type, Material::Type::kGlossy);
    EXPECT_EQ(m[1].distribution, Material::Distribution::kBeckmann);
    EXPECT_FLOAT_EQ(m[1].roughness, 0.3f);
    EXPECT_FALSE(m[1].conductor);
    EXPECT_EQ(m[2].distribution, Material::Distribution::kGgx);
    EXPECT_TRUE(m[2].conductor);
    EXPECT_EQ(m[2].eta, Rgb(0.18f, 0.42f, 1.37f));
    EXPECT_EQ(m[2].k, Rgb(3.42f, 2.35f, 1.77f));
    EXPECT_EQ(m[3].type, Material::Type::kDielectric);
    EXPECT_FLOAT_EQ(m[3].ior, 1.5f);
    EXPECT_FALSE(m[3].IsEmissive());
}

TEST_F(SceneLoaderTest, ObjMeshWithTransformAndMirroredPly) {
    Write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    Write("tri.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        R"({"type": "mesh", "material": "lamp", "file": "tri.obj",
            "transform": {"scale": 2, "rotate": {"axis": [0, 0, 3], "angle_deg": 90},
                          "translate": [10, 0, 0]}},
           {"type": "mesh", "material": "lamp", "file": "tri.obj"},
           {"type": "mesh", "material": "lamp", "file": "tri.ply",
            "transform": {"matrix": [-1, 0, 0, 5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->meshes.size(), 3u);
    const TriangleMesh& moved = scene->meshes[0];
    ExpectNear(moved.positions[0], {10, 0, 0});
    ExpectNear(moved.positions[1], {10, 2, 0});  // (1,0,0) scaled to 2, turned onto +y
    ExpectNear(moved.positions[2], {8, 0, 0});
    ExpectNear(FrontNormal(moved, 0), {0, 0, 1});
    EXPECT_EQ(scene->meshes[1].positions[1], Vec3d(1, 0, 0));  // the same file, untransformed
    // A mirroring matrix reverses the winding so the front face still faces +z.
    const TriangleMesh& mirrored = scene->meshes[2];
    EXPECT_EQ(mirrored.positions[1], Vec3d(4, 0, 0));
    EXPECT_EQ(mirrored.triangles[0], (std::array<uint32_t, 3>{0, 2, 1}));
    ExpectNear(FrontNormal(mirrored, 0), {0, 0, 1});
}

TEST_F(SceneLoaderTest, DegenerateTrianglesAreDroppedAndCountedOnce) {
    Write("slivers.obj",
          "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n"
          "f 1 2 3\n"    // fine
          "f 1 2 4\n"    // collinear
          "f 1 1 3\n");  // repeated vertex
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        R"({"type": "mesh", "material": "lamp", "file": "slivers.obj"},
           {"type": "quad", "material": "lamp",
            "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 0]]})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->dropped_degenerate, 3);
    EXPECT_EQ(scene->meshes[0].triangles.size(), 1u);
    EXPECT_EQ(scene->meshes[1].triangles.size(), 1u);
    EXPECT_FALSE(scene->meshes[1].is_quad);
    const std::string log = CapturedLog().str();
    EXPECT_EQ(Count(log, "degenerate"), 1u) << log;
    EXPECT_NE(log.find("scene.json: dropped 3 degenerate triangles"), std::string::npos) << log;

    ExpectError(SceneJson(kQuad + std::string(R"(, {"type": "triangle", "material": "lamp",
                          "vertices": [[0, 0, 0], [1, 1, 1], [2, 2, 2]]})")),
                "scene.json: shapes[1]: every triangle is degenerate");
}

TEST_F(SceneLoaderTest, HashCoversSceneAndMeshFiles) {
    auto hash = [&](const std::string& json) {
        absl::StatusOr<Scene> scene = Parse(json);
        EXPECT_TRUE(scene.ok()) << scene.status();
        return scene.ok() ? scene->content_hash : "";
    };
    const std::string json = SceneJson(R"({"type": "mesh", "material": "lamp", "file": "m.obj"})");
    Write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string first = hash(json);
    EXPECT_EQ(first.size(), 32u);
    EXPECT_EQ(hash(json), first);
    Write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 2 0\nf 1 2 3\n");
    const std::string second = hash(json);
    EXPECT_NE(second, first);
    EXPECT_NE(hash(json + " "), second);
}

TEST_F(SceneLoaderTest, HashIsFnv1a128OfSceneThenEachDistinctMesh) {
    Write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    // The expected value is FNV-1a 128 of this text followed by m.obj's bytes once, computed
    // independently of the loader.
    absl::StatusOr<Scene> scene =
        Parse(R"({"camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov_y_deg": 40, )"
              R"("resolution": [1, 1]}, "materials": {"m": {"type": "lambert", "reflectance": [0, )"
              R"(0, 0], )"
              R"("emission": [1, 1, 1]}}, "shapes": [{"type": "mesh", "material": "m", )"
              R"("file": "m.obj"}, )"
              R"({"type": "mesh", "material": "m", "file": "./m.obj"}]})");
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->content_hash, "aa5acf65cb94a21cd44b852a04c71373");
}

TEST_F(SceneLoaderTest, UnknownKeysAreWarningsNamingThePath) {
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        R"({"type": "quad", "material": "lamp", "colour": "red",
            "vertices": [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]]})",
        kMaterials, kCamera, R"(, "integrator": "path")"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    const std::string log = CapturedLog().str();
    EXPECT_NE(log.find("scene.json: shapes[0].colour: unknown key"), std::string::npos) << log;
    EXPECT_NE(log.find("scene.json: integrator: unknown key"), std::string::npos) << log;
}

TEST_F(SceneLoaderTest, NoLightIsAWarning) {
    ASSERT_TRUE(Parse(SceneJson(R"({"type": "quad", "material": "white",
                                    "vertices": [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]]})"))
                    .ok());
    EXPECT_NE(CapturedLog().str().find("no emissive shape and no light"), std::string::npos);
}

TEST_F(SceneLoaderTest, MissingSceneFile) {
    absl::StatusOr<Scene> scene = LoadScene((dir_ / "nope.json").string());
    ASSERT_FALSE(scene.ok());
    EXPECT_TRUE(absl::IsNotFound(scene.status()));
    EXPECT_NE(scene.status().message().find("nope.json"), std::string::npos);
}

TEST_F(SceneLoaderTest, JsonSyntaxErrorsNameLineAndColumn) {
    ExpectError("{\n  \"camera\": {\n    \"position\": [0, 0,, 1]",
                "scene.json:3:23: JSON syntax error");
    ExpectError("{\n  \"a\": [1e400]}", "scene.json:2:13: JSON syntax error: number overflow");
    ExpectError("{\"a\": NaN}", "scene.json:1:7: JSON syntax error");
    ExpectError("", "scene.json:1:1: JSON syntax error");
}

TEST_F(SceneLoaderTest, StructureErrorsNameThePath) {
    ExpectError("[]", "scene.json: expected an object, got array");
    ExpectError(R"({"materials": {}, "shapes": []})",
                "scene.json: missing required key \"camera\"");
    ExpectError(SceneJson(""), "scene.json: shapes: no shapes");
    ExpectError(R"({"camera": )" + std::string(kCamera) + R"(, "materials": {}, "shapes": {}})",
                "scene.json: shapes: expected an array, got object");
    ExpectError(SceneJson(kQuad, kMaterials, kCamera, R"(, "version": 2)"),
                "scene.json: version: unsupported");
    ExpectError(
        SceneJson(R"({"type": "quad", "material": "lamp", "vertices": [["0", 0, 0], [0, 0, 1], )"
                  R"([1, 0, 1], [1, 0, 0]]})"),
        "scene.json: shapes[0].vertices[0][0]: expected a number, got string \"0\"");
    ExpectError(
        SceneJson(R"({"type": "quad", "material": "lamp", "vertices": [[0, 0, 0], [0, 0, 1], [1, )"
                  R"(0, 1e16], [1, 0, 0]]})"),
        "scene.json: shapes[0].vertices[2][2]: must be within ±1e15, got 1e+16");
    ExpectError(
        SceneJson(R"({"type": "quad", "material": "lamp", "vertices": [[0, 0, 0], [0, 0, 1], [1, )"
                  R"(0, 1]]})"),
        "scene.json: shapes[0].vertices: expected 4 elements, got 3");
    ExpectError(
        SceneJson(R"({"type": "triangle", "material": "lamp", "vertices": [[0, 0, 0], [0, 0, 1], )"
                  R"([1, 0]]})"),
        "scene.json: shapes[0].vertices[2]: expected 3 elements, got 2");
    ExpectError(SceneJson(R"({"type": "triangle", "material": "gold", "vertices": []})"),
                "scene.json: shapes[0].material: unknown material \"gold\"");
    ExpectError(SceneJson(R"({"type": "cone", "material": "lamp"})"),
                "scene.json: shapes[0].type: unknown shape type \"cone\"");
    ExpectError(SceneJson(R"({"material": "lamp"})"),
                "scene.json: shapes[0]: missing required key \"type\"");
    ExpectError(
        SceneJson(R"({"type": "sphere", "material": "lamp", "center": [0, 0, 0], "radius": 0})"),
        "scene.json: shapes[0].radius: must be in (0, 1e15]");
    ExpectError(SceneJson(kQuad, kMaterials, kCamera,
                          R"(, "lights": [{"type": "area", "position": [0, 0, 0]}])"),
                "scene.json: lights[0].type: unknown light type \"area\"; expected point, spot, "
                "directional or environment");
    ExpectError(
        SceneJson(kQuad, kMaterials, kCamera,
                  R"(, "lights": [{"type": "point", "position": [0, 0, 0], "power": [1, 1, 1], )"
                  R"("intensity": [1, 1, 1]}])"),
        "scene.json: lights[0]: give exactly one of intensity (W/sr), power (W), intensity_cd (cd) "
        "or power_lm (lm)");
}

TEST_F(SceneLoaderTest, MaterialErrorsNameThePath) {
    ExpectError(WithMaterial(R"({"type": "metal"})"),
                "scene.json: materials.m.type: unknown material type \"metal\"");
    ExpectError(WithMaterial(R"({"type": "lambert"})"),
                "scene.json: materials.m: missing required key \"reflectance\"");
    ExpectError(WithMaterial(R"({"type": "mirror", "reflectance": [1, 1.5, 1]})"),
                "scene.json: materials.m.reflectance[1]: must be in [0, 1], got 1.5");
    ExpectError(
        WithMaterial(R"({"type": "lambert", "reflectance": [1, 1, 1], "emission": [-1, 0, 0]})"),
        "scene.json: materials.m.emission[0]: must be ≥ 0");
    // Absurdly bright: the light sampler's power would overflow and the film would clamp.
    ExpectError(
        WithMaterial(R"({"type": "lambert", "reflectance": [1, 1, 1], "emission": [1, 3e38, 0]})"),
        "scene.json: materials.m.emission[1]: must be ≥ 0 and at most 1e+10, got 3e+38");
    ExpectError(WithMaterial(R"({"type": "glossy", "roughness": 0, "reflectance": [1, 1, 1]})"),
                "scene.json: materials.m.roughness: must be a positive float, got 0");
    ExpectError(WithMaterial(R"({"type": "glossy", "roughness": 0.1, "distribution": "phong", )"
                             R"("reflectance": [1, 1, 1]})"),
                "scene.json: materials.m.distribution: unknown distribution \"phong\"");
    ExpectError(WithMaterial(R"({"type": "glossy", "roughness": 0.1, "reflectance": [1, 1, 1], )"
                             R"("eta": [1, 1, 1], "k": [0, 0, 0]})"),
                "scene.json: materials.m: give either reflectance or eta and k, not both");
    ExpectError(WithMaterial(R"({"type": "glossy", "roughness": 0.1, "eta": [1, 1, 1]})"),
                "scene.json: materials.m: missing required key \"k\"");
    ExpectError(WithMaterial(R"({"type": "dielectric", "ior": -1.5})"),
                "scene.json: materials.m.ior: must be a positive float");
    ExpectError(WithMaterial("[]"), "scene.json: materials.m: expected an object, got array");
}

// "type": "orthographic" takes the film's half height in place of a field of view.
TEST_F(SceneLoaderTest, OrthographicCameraTakesAHalfHeight) {
    auto with_camera = [](const std::string& fields) {
        return SceneJson(
            kQuad, kMaterials,
            R"({"position": [0, 0, -5], "look_at": [0, 0, 0], "resolution": [8, 4], )" + fields +
                "}");
    };
    const absl::StatusOr<Scene> scene =
        Parse(with_camera(R"("type": "orthographic", "half_height": 2.5)"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->camera.projection, CameraSpec::Projection::kOrthographic);
    EXPECT_DOUBLE_EQ(scene->camera.half_height, 2.5);
    ExpectError(with_camera(R"("type": "orthographic")"),
                "scene.json: camera: missing required key \"half_height\"");
    ExpectError(with_camera(R"("type": "orthographic", "half_height": 1, "fov_y_deg": 40)"),
                "scene.json: camera.fov_y_deg: has no meaning for an orthographic camera");
    ExpectError(with_camera(R"("type": "fisheye", "fov_y_deg": 40)"),
                "scene.json: camera.type: unknown camera type \"fisheye\"; expected perspective "
                "or orthographic");
    ExpectError(with_camera(R"("half_height": 1, "fov_y_deg": 40)"),
                "scene.json: camera.half_height: is for orthographic cameras");
}

TEST_F(SceneLoaderTest, CameraErrorsNameThePath) {
    auto with_camera = [](const std::string& fields) {
        return SceneJson(kQuad, kMaterials, "{" + fields + "}");
    };
    const std::string base = R"("position": [0, 0, -5], "fov_y_deg": 40, )";
    ExpectError(with_camera(base + R"("look_at": [0, 0, -5], "resolution": [8, 8])"),
                "scene.json: camera.look_at: equals camera.position");
    ExpectError(
        with_camera(base + R"("look_at": [0, 0, 0], "up": [0, 0, 2], "resolution": [8, 8])"),
        "scene.json: camera.up: is zero or parallel to the view direction");
    ExpectError(with_camera(R"("position": [0, 0, 0], "look_at": [0, 3, 0], "fov_y_deg": 40, )"
                            R"("resolution": [8, 8])"),
                "scene.json: camera: the default up [0, 1, 0] is parallel");
    ExpectError(with_camera(R"("position": [0, 0, -5], "look_at": [0, 0, 0], "fov_y_deg": 180, )"
                            R"("resolution": [8, 8])"),
                "scene.json: camera.fov_y_deg: must be in (0, 180) degrees, got 180");
    ExpectError(with_camera(base + R"("look_at": [0, 0, 0])"),
                "scene.json: camera: missing required key \"resolution\"");
    ExpectError(with_camera(base + R"("look_at": [0, 0, 0], "resolution": [100000, 8])"),
                "scene.json: camera.resolution[0]: must be an integer in [1, 65536], got 100000");
    ExpectError(with_camera(base + R"("look_at": [0, 0, 0], "resolution": [8.5, 8])"),
                "scene.json: camera.resolution[0]: must be an integer, got 8.5");
    ExpectError(with_camera(base + R"("look_at": [0, 0, 0], "resolution": [65536, 65536])"),
                "scene.json: camera.resolution: 65536 x 65536 is more than 2^28 pixels");
}

TEST_F(SceneLoaderTest, MeshErrorsNameTheShapeAndTheFile) {
    auto mesh_shape = [](const std::string& file, const std::string& extra = "") {
        return SceneJson(kQuad +
                         std::string(R"(, {"type": "mesh", "material": "lamp", "file": ")") + file +
                         "\"" + extra + "}");
    };
    ExpectError(mesh_shape("missing.obj"),
                "scene.json: shapes[1].file \"missing.obj\": ", absl::StatusCode::kNotFound);
    ExpectError(mesh_shape("missing.obj"), "missing.obj: cannot open", absl::StatusCode::kNotFound);
    Write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    ExpectError(mesh_shape("range.obj"), "range.obj:4: face refers to vertex 9");
    ExpectError(mesh_shape("range.obj"), "scene.json: shapes[1].file: ");
    Write("empty.obj", "v 0 0 0\n");
    ExpectError(mesh_shape("empty.obj"), "empty.obj: no faces");
    Write("nan.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n");
    ExpectError(mesh_shape("nan.obj"), "nan.obj:2: vertex 2 is not finite");
    Write("far.obj", "v 0 0 0\nv 1e16 0 0\nv 0 1 0\nf 1 2 3\n");
    ExpectError(mesh_shape("far.obj"), "scene.json: shapes[1]: a vertex of ");
    Write("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    ExpectError(mesh_shape("ok.obj", R"(, "transform": {"scale": [1, 0, 1]})"),
                "scene.json: shapes[1].transform: singular");
    ExpectError(
        mesh_shape("ok.obj",
                   R"(, "transform": {"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], )"
                   R"("translate": [1, 0, 0]})"),
        "scene.json: shapes[1].transform: give either matrix or scale/rotate/translate");
    ExpectError(
        mesh_shape(
            "ok.obj",
            R"(, "transform": {"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]})"),
        "scene.json: shapes[1].transform.matrix: the last row must be [0, 0, 0, 1]");
    ExpectError(
        mesh_shape("ok.obj", R"(, "transform": {"rotate": {"axis": [0, 0, 0], "angle_deg": 5}})"),
        "scene.json: shapes[1].transform.rotate.axis: must not be zero");
}

// A 2 x 1 RGBA PNG: an opaque red texel and a half-transparent blue one.
std::string TexturePng() {
    return lf::testing::PngBytes(2, 1, 4, {255, 0, 0, 255, 0, 0, 255, 128});
}

constexpr char kMtl[] =
    "newmtl wood\n"
    "Kd 1 1 1\n"
    "map_Kd wood.png\n"
    "newmtl lamp\n"
    "Kd 0 0 0\n"
    "Ke 5 5 5\n"
    "newmtl veil\n"
    "Kd 0.5 0.5 0.5\n"
    "d 0.25\n";

// Two triangles in the z = 0 plane, smooth normals tilted in x, texture coordinates, three
// materials of the MTL file.
constexpr char kObj[] =
    "mtllib m.mtl\n"
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
    "vn 1 0 1\nvn 0 0 1\n"
    "vt 0 0\nvt 1 0\nvt 0 1\n"
    "usemtl wood\nf 1/1/1 2/2/2 3/3/2\n"
    "usemtl lamp\nf 2/2/2 4/1/2 3/3/2\n"
    "usemtl veil\nf 3/3/2 2/2/2 4/1/1\n";

// map_Ke alone emits the texture (as a JSON emission_texture alone does); with Ke, the two
// multiply.
TEST_F(SceneLoaderTest, MtlEmissionMapWithoutKeEmitsTheTexture) {
    Write("glow.png", lf::testing::PngBytes(1, 1, 3, {255, 255, 255}));
    Write("g.obj",
          "mtllib g.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
          "usemtl alone\nf 1/1 2/2 3/3\nusemtl dim\nf 1/1 3/3 2/2\n");
    Write("g.mtl", "newmtl alone\nmap_Ke glow.png\nnewmtl dim\nKe 0.5 0.5 0.5\nmap_Ke glow.png\n");
    absl::StatusOr<Scene> scene = Parse(SceneJson(R"({"type": "mesh", "file": "g.obj"})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    const auto material = [&](const std::string& name) -> const Material& {
        for (const Material& m : scene->materials) {
            if (m.name == "g.mtl#" + name) return m;
        }
        ADD_FAILURE() << "no material " << name;
        return scene->materials[0];
    };
    EXPECT_EQ(material("alone").emission, Rgb(1));
    EXPECT_TRUE(material("alone").emission_texture.valid());
    EXPECT_EQ(material("dim").emission, Rgb(0.5f));
}

// A thin-lens camera focuses on what it looks at unless told otherwise; a negative aperture or a
// zero focus distance is an error naming the key.
TEST_F(SceneLoaderTest, ThinLensCameraKeys) {
    const std::string lens =
        R"({"position": [0, 0, -5], "look_at": [0, 0, 0], "fov_y_deg": 40,
            "resolution": [32, 24], "aperture_radius": 0.05)";
    absl::StatusOr<Scene> scene = Parse(SceneJson(kQuad, kMaterials, lens + "}"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->camera.aperture_radius, 0.05);
    EXPECT_EQ(scene->camera.focus_distance, 5);
    scene = Parse(SceneJson(kQuad, kMaterials, lens + R"(, "focus_distance": 2.5})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->camera.focus_distance, 2.5);
    ExpectError(SceneJson(kQuad, kMaterials,
                          R"({"position": [0, 0, -5], "look_at": [0, 0, 0], "fov_y_deg": 40,
                              "resolution": [32, 24], "aperture_radius": -1})"),
                "scene.json: camera.aperture_radius: must be ≥ 0 (scene units), got -1");
    ExpectError(SceneJson(kQuad, kMaterials, lens + R"(, "focus_distance": 0})"),
                "scene.json: camera.focus_distance: must be above 0 (scene units)");
}

// A normal map needs tangents; an OBJ has none, so the loader computes them once, per vertex,
// after the shape's transform: here u runs along +x scaled by 2, and v down the image along -y.
TEST_F(SceneLoaderTest, NormalMappedMeshesWithoutTangentsGetThemAtLoad) {
    Write("bumps.png", lf::testing::PngBytes(1, 1, 3, {128, 128, 255}));
    Write("q.obj",
          "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
          "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        R"({"type": "mesh", "file": "q.obj", "material": "bumpy",
            "transform": {"scale": [2, 1, 1]}},
           {"type": "mesh", "file": "q.obj", "material": "flat"})",
        R"({"bumpy": {"type": "principled", "normal_texture": "bumps.png"},
            "flat": {"type": "principled"}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    const TriangleMesh& bumpy = scene->meshes[0];
    ASSERT_EQ(bumpy.tangents.size(), bumpy.positions.size());
    for (const auto& t : bumpy.tangents) {
        EXPECT_NEAR(t[0], 1, 1e-6);
        EXPECT_NEAR(t[1], 0, 1e-6);
        EXPECT_NEAR(t[2], 0, 1e-6);
        // The bitangent cross(n, t) = (0, 1, 0) points up the image, towards decreasing v.
        EXPECT_EQ(t[3], 1);
    }
    EXPECT_TRUE(scene->meshes[1].tangents.empty());  // no normal map, no need
}

TEST_F(SceneLoaderTest, ObjWithMtlBringsItsMaterialsAndTextures) {
    Write("m.obj", kObj);
    Write("m.mtl", kMtl);
    Write("wood.png", TexturePng());
    // Scale x by 2: the normal (1, 0, 1) goes by the inverse transpose to (0.5, 0, 1).
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        R"({"type": "mesh", "name": "obj", "file": "m.obj", "transform": {"scale": [2, 1, 1]}},
           {"type": "quad", "material": "white", "vertices": [[0, 0, 1], [1, 0, 1], [1, 1, 1],
            [0, 1, 1]]})",
        R"({"white": {"type": "lambert", "base_color_texture": "./wood.png"}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    // The JSON's material first, then the file's in the order its faces use them.
    ASSERT_EQ(scene->materials.size(), 4u);
    EXPECT_EQ(scene->materials[1].name, "m.mtl#wood");
    EXPECT_EQ(scene->materials[2].name, "m.mtl#lamp");
    EXPECT_EQ(scene->materials[3].name, "m.mtl#veil");
    // wood.png once for the JSON's "./wood.png" and the MTL's "wood.png".
    ASSERT_EQ(scene->textures.size(), 1u);
    EXPECT_EQ(scene->textures[0]->width, 2);
    EXPECT_EQ(scene->materials[0].base_color_texture.image, 0);
    EXPECT_EQ(scene->materials[0].reflectance, Rgb(1));
    const Material& wood = scene->materials[1];
    EXPECT_EQ(wood.type, Material::Type::kLambert);
    EXPECT_EQ(wood.base_color_texture.image, 0);
    EXPECT_TRUE(wood.base_color_texture.srgb);
    EXPECT_EQ(scene->materials[2].emission, Rgb(5));
    EXPECT_EQ(scene->materials[3].alpha_mode, Material::AlphaMode::kMask);
    EXPECT_FLOAT_EQ(scene->materials[3].opacity, 0.25f);

    ASSERT_EQ(scene->meshes.size(), 4u);
    const TriangleMesh& first = scene->meshes[0];
    EXPECT_EQ(first.name, "obj (m.mtl#wood)");
    EXPECT_EQ(first.material, 1);
    EXPECT_EQ(scene->meshes[1].material, 2);
    EXPECT_EQ(scene->meshes[2].material, 3);
    EXPECT_EQ(scene->meshes[3].material, 0);
    ASSERT_EQ(first.positions.size(), 3u);
    EXPECT_EQ(first.positions[1], Vec3d(2, 0, 0));
    ASSERT_EQ(first.normals.size(), 3u);
    const Vec3 tilted = Normalize(Vec3(0.5f, 0, 1));
    EXPECT_FLOAT_EQ(first.normals[0].x, tilted.x);
    EXPECT_FLOAT_EQ(first.normals[0].y, 0);
    EXPECT_FLOAT_EQ(first.normals[0].z, tilted.z);
    EXPECT_EQ(first.normals[1], Vec3(0, 0, 1));
    ASSERT_EQ(first.uvs.size(), 3u);
    EXPECT_FLOAT_EQ(first.uvs[0].y, 1);  // vt 0 0: the bottom of the image
    EXPECT_FLOAT_EQ(first.uvs[2].y, 0);

    // The MTL file and the texture count in the content hash.
    const std::string json = SceneJson(R"({"type": "mesh", "file": "m.obj"})");
    absl::StatusOr<Scene> before = Parse(json);
    ASSERT_TRUE(before.ok()) << before.status();
    Write("m.mtl", std::string(kMtl) + "\n");
    absl::StatusOr<Scene> after_mtl = Parse(json);
    ASSERT_TRUE(after_mtl.ok()) << after_mtl.status();
    EXPECT_NE(after_mtl->content_hash, before->content_hash);
    Write("wood.png", lf::testing::PngBytes(1, 1, 3, {1, 2, 3}));
    absl::StatusOr<Scene> after_png = Parse(json);
    ASSERT_TRUE(after_png.ok()) << after_png.status();
    EXPECT_NE(after_png->content_hash, after_mtl->content_hash);
}

TEST_F(SceneLoaderTest, AMeshShapesMaterialOverridesTheFiles) {
    Write("m.obj", kObj);  // its MTL file is not even there: not read
    absl::StatusOr<Scene> scene =
        Parse(SceneJson(R"({"type": "mesh", "material": "lamp", "file": "m.obj"})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->meshes.size(), 1u);
    EXPECT_EQ(scene->meshes[0].material, 1);
    EXPECT_EQ(scene->meshes[0].triangles.size(), 3u);
    EXPECT_EQ(scene->materials.size(), 2u);
    EXPECT_TRUE(scene->textures.empty());
}

TEST_F(SceneLoaderTest, ObjMaterialErrorsNameTheFileAndLine) {
    const std::string json = SceneJson(R"({"type": "mesh", "file": "m.obj"})");
    Write("m.obj", kObj);
    ExpectError(json, "scene.json: shapes[0].file: m.obj:1: mtllib \"m.mtl\": ",
                absl::StatusCode::kInvalidArgument);
    Write("m.mtl", kMtl);
    ExpectError(json, "scene.json: shapes[0].file \"m.obj\": m.mtl:3: map_Kd \"wood.png\": ",
                absl::StatusCode::kNotFound);
    Write("wood.png", "not a png");
    ExpectError(json, "scene.json: shapes[0].file \"m.obj\": m.mtl:3: map_Kd: ");
    Write("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    ExpectError(SceneJson(R"({"type": "mesh", "file": "plain.obj"})"),
                "scene.json: shapes[0]: missing required key \"material\": the faces of "
                "plain.obj:4 have no material from the file");
    Write("plain.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    ExpectError(SceneJson(R"({"type": "mesh", "file": "plain.ply"})"),
                "scene.json: shapes[0]: missing required key \"material\": the faces of "
                "plain.ply have no material");
    ExpectError(SceneJson(R"({"type": "quad", "vertices": []})"),
                "scene.json: shapes[0]: missing required key \"material\"");
}

TEST_F(SceneLoaderTest, PrincipledMaterialAndTextures) {
    Write("wood.png", TexturePng());
    Write("mr.png", lf::testing::PngBytes(1, 1, 3, {0, 128, 255}));
    absl::StatusOr<Scene> scene = Parse(
        SceneJson(kQuad,
                  R"({"lamp": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [1, 1, 1]},
            "plain": {"type": "principled"},
            "car_paint": {"type": "principled", "base_color": [0.5, 0.1, 0.1], "metallic": 0.3,
                "roughness": 0.2, "specular": 0.7, "ior": 1.45, "transmission": 0.25,
                "thickness": 0.01, "attenuation_color": [0.9, 0.8, 0.7],
                "attenuation_distance": 0.5, "opacity": 0.6, "alpha_mode": "mask",
                "alpha_cutoff": 0.3, "double_sided": false, "emission": [0.1, 0.2, 0.3],
                "clearcoat": 0.5, "clearcoat_roughness": 0.1, "sheen_color": [0.2, 0.3, 0.4],
                "sheen_roughness": 0.6,
                "base_color_texture": {"file": "wood.png", "wrap": "mirror", "filter": "nearest",
                    "transform": {"offset": [0.5, 0.25], "rotation_deg": 90,
                                  "scale": [2, -1]}},
                "metallic_roughness_texture": "mr.png",
                "normal_texture": {"file": "mr.png", "wrap": "clamp"}, "normal_scale": 0.5,
                "emission_texture": "wood.png"},
            "glow": {"type": "principled", "emission_texture": "wood.png",
                "alpha_mode": "blend"}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_TRUE(CapturedLog().str().empty()) << CapturedLog().str();
    ASSERT_EQ(scene->textures.size(), 2u);
    const Material& plain = scene->materials[1];
    EXPECT_EQ(plain.type, Material::Type::kPrincipled);
    EXPECT_EQ(plain.reflectance, Rgb(0.8f));
    EXPECT_FLOAT_EQ(plain.metallic, 0);
    EXPECT_FLOAT_EQ(plain.roughness, 0.5f);
    EXPECT_FLOAT_EQ(plain.specular, 1);
    EXPECT_FLOAT_EQ(plain.ior, 1.5f);
    EXPECT_FALSE(plain.IsTextured());
    EXPECT_FALSE(plain.IsEmissive());

    const Material& m = scene->materials[2];
    EXPECT_FLOAT_EQ(m.clearcoat, 0.5f);
    EXPECT_FLOAT_EQ(m.clearcoat_roughness, 0.1f);
    EXPECT_EQ(m.sheen_color, Rgb(0.2f, 0.3f, 0.4f));
    EXPECT_FLOAT_EQ(m.sheen_roughness, 0.6f);
    EXPECT_EQ(m.reflectance, Rgb(0.5f, 0.1f, 0.1f));
    EXPECT_FLOAT_EQ(m.metallic, 0.3f);
    EXPECT_FLOAT_EQ(m.roughness, 0.2f);
    EXPECT_FLOAT_EQ(m.specular, 0.7f);
    EXPECT_FLOAT_EQ(m.ior, 1.45f);
    EXPECT_FLOAT_EQ(m.transmission, 0.25f);
    EXPECT_FLOAT_EQ(m.thickness, 0.01f);
    EXPECT_EQ(m.attenuation_color, Rgb(0.9f, 0.8f, 0.7f));
    EXPECT_FLOAT_EQ(m.attenuation_distance, 0.5f);
    EXPECT_FLOAT_EQ(m.opacity, 0.6f);
    EXPECT_EQ(m.alpha_mode, Material::AlphaMode::kMask);
    EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.3f);
    EXPECT_FALSE(m.double_sided);
    EXPECT_EQ(m.emission, Rgb(0.1f, 0.2f, 0.3f));
    const TextureRef& base = m.base_color_texture;
    EXPECT_EQ(base.image, 0);
    EXPECT_TRUE(base.srgb);
    EXPECT_TRUE(base.nearest);
    EXPECT_EQ(base.wrap_s, TextureRef::Wrap::kMirroredRepeat);
    EXPECT_EQ(base.wrap_t, TextureRef::Wrap::kMirroredRepeat);
    EXPECT_FLOAT_EQ(base.offset.x, 0.5f);
    EXPECT_FLOAT_EQ(base.offset.y, 0.25f);
    EXPECT_FLOAT_EQ(base.rotation, float(std::numbers::pi / 2));
    EXPECT_FLOAT_EQ(base.scale.x, 2);
    EXPECT_FLOAT_EQ(base.scale.y, -1);
    EXPECT_EQ(m.metallic_roughness_texture.image, 1);
    EXPECT_FALSE(m.metallic_roughness_texture.srgb);
    EXPECT_EQ(m.normal_texture.image, 1);
    EXPECT_FALSE(m.normal_texture.srgb);
    EXPECT_EQ(m.normal_texture.wrap_s, TextureRef::Wrap::kClampToEdge);
    EXPECT_FLOAT_EQ(m.normal_scale, 0.5f);
    EXPECT_EQ(m.emission_texture.image, 0);
    EXPECT_TRUE(m.emission_texture.srgb);
    // An emission texture alone is the radiance: its factor defaults to 1.
    EXPECT_EQ(scene->materials[3].emission, Rgb(1));
    EXPECT_EQ(scene->materials[3].reflectance, Rgb(0.8f));
    EXPECT_EQ(scene->materials[3].alpha_mode, Material::AlphaMode::kBlend);
}

TEST_F(SceneLoaderTest, PrincipledErrorsNameThePath) {
    Write("wood.png", TexturePng());
    const std::string p = R"({"type": "principled", )";
    ExpectError(WithMaterial(p + R"("metallic": 2})"),
                "scene.json: materials.m.metallic: must be in [0, 1], got 2");
    ExpectError(WithMaterial(p + R"("roughness": -0.1})"),
                "scene.json: materials.m.roughness: must be in [0, 1], got -0.1");
    ExpectError(WithMaterial(p + R"("transmission": 1.5})"),
                "scene.json: materials.m.transmission: must be in [0, 1], got 1.5");
    ExpectError(WithMaterial(p + R"("ior": 0})"),
                "scene.json: materials.m.ior: must be a positive float, got 0");
    ExpectError(WithMaterial(p + R"("thickness": -1})"),
                "scene.json: materials.m.thickness: must be ≥ 0 (metres), got -1");
    ExpectError(WithMaterial(p + R"("attenuation_distance": 0})"),
                "scene.json: materials.m.attenuation_distance: must be a positive float");
    ExpectError(WithMaterial(p + R"("base_color": [1, 1, 2]})"),
                "scene.json: materials.m.base_color[2]: must be in [0, 1], got 2");
    ExpectError(WithMaterial(p + R"("base_color": [1, 1, 1], "reflectance": [1, 1, 1]})"),
                "scene.json: materials.m: give either base_color or reflectance");
    ExpectError(WithMaterial(p + R"("alpha_mode": "add"})"),
                "scene.json: materials.m.alpha_mode: unknown alpha mode \"add\"; expected "
                "opaque, mask or blend");
    ExpectError(WithMaterial(p + R"("double_sided": "yes"})"),
                "scene.json: materials.m.double_sided: expected true or false, got string");
    ExpectError(
        WithMaterial(p + R"("base_color_texture": "nope.png"})"),
        "scene.json: materials.m.base_color_texture \"nope.png\": ", absl::StatusCode::kNotFound);
    ExpectError(
        WithMaterial(p + R"("normal_texture": {"file": "nope.png"}})"),
        "scene.json: materials.m.normal_texture.file \"nope.png\": ", absl::StatusCode::kNotFound);
    ExpectError(WithMaterial(p + R"("base_color_texture": {"file": "wood.png", "wrap": "tile"}})"),
                "scene.json: materials.m.base_color_texture.wrap: unknown wrap mode \"tile\"; "
                "expected repeat, clamp or mirror");
    ExpectError(
        WithMaterial(p + R"("base_color_texture": {"file": "wood.png", "filter": "cubic"}})"),
        "scene.json: materials.m.base_color_texture.filter: unknown filter \"cubic\"");
    ExpectError(WithMaterial(p + R"("base_color_texture": {"file": "wood.png", )"
                                 R"("transform": {"scale": [1, 0]}}})"),
                "scene.json: materials.m.base_color_texture.transform.scale: must not be zero");
    ExpectError(WithMaterial(p + R"("base_color_texture": {"wrap": "clamp"}})"),
                "scene.json: materials.m.base_color_texture: missing required key \"file\"");
    Write("bad.png", "GIF89a not a png");
    ExpectError(WithMaterial(p + R"("base_color_texture": "bad.png"})"),
                "scene.json: materials.m.base_color_texture: ");
    ExpectError(WithMaterial(R"({"type": "lambert", "reflectance": [1, 1, 1], )"
                             R"("base_color_texture": 7})"),
                "scene.json: materials.m.base_color_texture: expected an object, got number");
}

TEST_F(SceneLoaderTest, SpotAndDirectionalLights) {
    const double pi = std::numbers::pi;
    absl::StatusOr<Scene> scene = Parse(SceneJson(kQuad, kMaterials, kCamera,
                                                  R"(, "lights": [
            {"type": "spot", "position": [0, 3, 0], "direction": [0, -2, 0],
             "intensity": [1, 2, 3], "inner_cone_deg": 20, "outer_cone_deg": 30},
            {"type": "spot", "position": [0, 3, 0], "direction": [1, 0, 0], "power": [10, 10, 10]},
            {"type": "spot", "position": [0, 3, 0], "direction": [1, 0, 0],
             "intensity_cd": 683, "color": [1, 0.5, 0]},
            {"type": "directional", "direction": [0, 0, -3], "irradiance": [2, 2, 2]},
            {"type": "directional", "direction": [1, -1, 0], "illuminance_lux": 1366,
             "color": [1, 1, 0.5]},
            {"type": "point", "position": [0, 1, 0], "intensity_cd": 68.3}])"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_TRUE(CapturedLog().str().empty()) << CapturedLog().str();
    ASSERT_EQ(scene->spot_lights.size(), 3u);
    const SpotLight& spot = scene->spot_lights[0];
    EXPECT_EQ(spot.position, Vec3d(0, 3, 0));
    EXPECT_EQ(spot.direction, Vec3d(0, -1, 0));
    EXPECT_EQ(spot.intensity, Rgb(1, 2, 3));
    EXPECT_DOUBLE_EQ(spot.inner_cone, 20 * pi / 180);
    EXPECT_DOUBLE_EQ(spot.outer_cone, 30 * pi / 180);
    EXPECT_EQ(spot.falloff, SpotLight::Falloff::kSmoothstep);
    // Power over the smoothstep falloff's solid angle 2 pi (1 - (cos i + cos o) / 2), with the
    // default cones 0 and 45 degrees (checked against quadrature in photometry_test.cc).
    const double c45 = std::cos(pi / 4);
    EXPECT_DOUBLE_EQ(scene->spot_lights[1].inner_cone, 0);
    EXPECT_DOUBLE_EQ(scene->spot_lights[1].outer_cone, pi / 4);
    EXPECT_NEAR(scene->spot_lights[1].intensity.g, 10 / (2 * pi * (1 - (1 + c45) / 2)), 1e-4);
    // 683 cd of colour (1, 0.5, 0), normalised to luminance 1 (its Y is 0.2126 + 0.7152 / 2).
    const float y = 0.2126f + 0.7152f * 0.5f;
    ExpectRgbNear(scene->spot_lights[2].intensity, Rgb(1 / y, 0.5f / y, 0));
    ASSERT_EQ(scene->directional_lights.size(), 2u);
    EXPECT_EQ(scene->directional_lights[0].direction, Vec3d(0, 0, -1));
    EXPECT_EQ(scene->directional_lights[0].irradiance, Rgb(2));
    ExpectNear(scene->directional_lights[1].direction, Normalize(Vec3d(1, -1, 0)));
    // 1366 lx of (1, 1, 0.5), luminance 0.2126 + 0.7152 + 0.0722 / 2.
    ExpectRgbNear(scene->directional_lights[1].irradiance, Rgb(2, 2, 1) / 0.9639f);
    ASSERT_EQ(scene->point_lights.size(), 1u);
    EXPECT_FLOAT_EQ(scene->point_lights[0].intensity.r, 0.1f);
}

TEST_F(SceneLoaderTest, LightErrorsNameThePath) {
    const std::string spot = R"({"type": "spot", "position": [0, 0, 0], "intensity": [1, 1, 1], )";
    ExpectError(WithLights(spot + R"("direction": [0, 0, 0]})"),
                "scene.json: lights[0].direction: must not be zero");
    ExpectError(WithLights(spot + R"("direction": [0, 0, 1], "inner_cone_deg": 30, )"
                                  R"("outer_cone_deg": 20})"),
                "scene.json: lights[0].outer_cone_deg: 20 must be above lights[0].inner_cone_deg "
                "(30)");
    ExpectError(WithLights(spot + R"("direction": [0, 0, 1], "outer_cone_deg": 95})"),
                "scene.json: lights[0].outer_cone_deg: must be in (0, 90] degrees, got 95");
    ExpectError(WithLights(spot + R"("direction": [0, 0, 1], "inner_cone_deg": -1})"),
                "scene.json: lights[0].inner_cone_deg: must be in [0, 90) degrees, got -1");
    ExpectError(WithLights(spot + R"("direction": [0, 0, 1], "outer_cone_deg": 0})"),
                "scene.json: lights[0].outer_cone_deg: 0 must be above the default inner_angle_deg "
                "(0)");
    ExpectError(WithLights(spot + R"("direction": [0, 0, 1], "color": [1, 0, 0]})"),
                "scene.json: lights[0].intensity: an [r, g, b] strength is a colour itself; with "
                "color or temperature_k give a number");
    ExpectError(WithLights(R"({"type": "spot", "position": [0, 0, 0], "intensity": [1, 1, 1]})"),
                "scene.json: lights[0]: missing required key \"direction\"");
    ExpectError(WithLights(R"({"type": "directional", "direction": [0, 0, 1]})"),
                "scene.json: lights[0]: give exactly one of irradiance (W/m^2) or "
                "illuminance_lux (lx)");
    ExpectError(WithLights(R"({"type": "directional", "direction": [0, 0, 1], )"
                           R"("illuminance_lux": -5})"),
                "scene.json: lights[0].illuminance_lux: must be ≥ 0");
    ExpectError(WithLights(R"({"type": "directional", "direction": [0, 0, 1], )"
                           R"("irradiance": [1, 1, 1], "color": [1, 1, 1]})"),
                "scene.json: lights[0].irradiance: an [r, g, b] strength is a colour itself");
    ExpectError(WithLights(R"({"type": "point", "position": [0, 0, 0], "intensity_cd": 1, )"
                           R"("color": [2, 1, 1]})"),
                "scene.json: lights[0].color[0]: must be in [0, 1], got 2");
}

// Photometric strengths of every light: the colour (given or a black body) at luminance 1,
// times the number, at 683 lm/W; radiometric numbers times the colour as given.
TEST_F(SceneLoaderTest, PhotometricLightsAndColourTemperatures) {
    const double pi = std::numbers::pi;
    absl::StatusOr<Scene> scene = Parse(SceneJson(kQuad, kMaterials, kCamera, R"(, "lights": [
        {"type": "point", "position": [0, 1, 0], "intensity_cd": 683, "color": [1, 1, 1]},
        {"type": "point", "position": [0, 1, 0], "intensity_cd": 683, "temperature_k": 2856},
        {"type": "point", "position": [0, 1, 0], "power_lm": 2732},
        {"type": "point", "position": [0, 1, 0], "intensity": 2, "temperature_k": 6500},
        {"type": "point", "position": [0, 1, 0], "intensity": 2, "color": [1, 0.5, 0.25]},
        {"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "power_lm": 683,
         "inner_angle_deg": 10, "outer_angle_deg": 40, "color": [0, 0, 1]},
        {"type": "directional", "direction": [0, -1, 0], "illuminance_lux": 100000,
         "temperature_k": 5800, "angular_diameter_deg": 0.53}])"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_TRUE(CapturedLog().str().empty()) << CapturedLog().str();
    ASSERT_EQ(scene->point_lights.size(), 5u);
    EXPECT_EQ(scene->point_lights[0].intensity, Rgb(1));  // 683 cd of white: 1 W/sr
    ExpectRgbNear(scene->point_lights[1].intensity, BlackbodyRgb(2856));
    EXPECT_NEAR(scene->point_lights[1].intensity.Luminance(), 1, 1e-6);
    // 2732 lm = 4 x 683 lm over the sphere's 4 pi sr: 683 / pi cd, 1 / pi W/sr.
    ExpectRgbNear(scene->point_lights[2].intensity, Rgb(float(1 / pi)));
    ExpectRgbNear(scene->point_lights[3].intensity, BlackbodyRgb(6500) * 2);
    EXPECT_EQ(scene->point_lights[4].intensity, Rgb(2, 1, 0.5f));  // radiometric: not normalised
    ASSERT_EQ(scene->spot_lights.size(), 1u);
    const SpotLight& spot = scene->spot_lights[0];
    EXPECT_DOUBLE_EQ(spot.inner_cone, 10 * pi / 180);
    EXPECT_DOUBLE_EQ(spot.outer_cone, 40 * pi / 180);
    // The smoothstep falloff's solid angle by quadrature over the cone (midpoint rule, 1e5
    // steps: relative error ~1e-10): 683 lm of luminance-1 blue over it.
    double solid_angle = 0;
    constexpr int kSteps = 100000;
    for (int i = 0; i < kSteps; ++i) {
        const double theta = (i + 0.5) / kSteps * spot.outer_cone;
        const double cos_inner = std::cos(spot.inner_cone), cos_outer = std::cos(spot.outer_cone);
        const double t =
            std::clamp((std::cos(theta) - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
        solid_angle += 2 * pi * std::sin(theta) * t * t * (3 - 2 * t) * spot.outer_cone / kSteps;
    }
    ExpectRgbNear(spot.intensity, Rgb(0, 0, float(1 / 0.0722 / solid_angle)));
    ASSERT_EQ(scene->directional_lights.size(), 1u);
    const DirectionalLight& sun = scene->directional_lights[0];
    ExpectRgbNear(sun.irradiance, BlackbodyRgb(5800) * float(100000 / 683.0));
    EXPECT_DOUBLE_EQ(sun.angular_diameter, 0.53 * pi / 180);
}

TEST_F(SceneLoaderTest, PhotometricAndColourErrorsNameThePath) {
    const std::string point = R"({"type": "point", "position": [0, 0, 0], )";
    ExpectError(WithLights(point + R"("intensity_cd": 1, "temperature_k": 0})"),
                "scene.json: lights[0].temperature_k: must be in [1000, 40000] kelvin, got 0");
    ExpectError(WithLights(point + R"("intensity_cd": 1, "temperature_k": 50000})"),
                "scene.json: lights[0].temperature_k: must be in [1000, 40000] kelvin, got 50000");
    ExpectError(WithLights(point + R"("intensity": [1, 1, 1], "power_lm": 5})"),
                "scene.json: lights[0]: give a radiometric strength (intensity or power) or a "
                "photometric one (intensity_cd or power_lm), not both");
    ExpectError(
        WithLights(point + R"("intensity_cd": 1, "color": [1, 1, 1], "temperature_k": 3000})"),
        "scene.json: lights[0]: give color or temperature_k, not both");
    ExpectError(WithLights(point + R"("intensity_cd": 1, "color": [0, 0, 0]})"),
                "scene.json: lights[0].color: has luminance 0: a photometric strength cannot give "
                "it any light");
    ExpectError(WithLights(R"({"type": "directional", "direction": [0, -1, 0], "irradiance": 1, )"
                           R"("angular_diameter_deg": 91})"),
                "scene.json: lights[0].angular_diameter_deg: must be in [0, 90] degrees, got 91");
    ExpectError(WithLights(R"({"type": "directional", "direction": [0, -1, 0], )"
                           R"("illuminance_lux": 1, "irradiance": [1, 1, 1]})"),
                "scene.json: lights[0]: give a radiometric strength (irradiance) or a photometric "
                "one (illuminance_lux), not both");
    const std::string spot =
        R"({"type": "spot", "position": [0, 0, 0], "direction": [0, 0, 1], "intensity": 1, )";
    ExpectError(WithLights(spot + R"("inner_angle_deg": 30, "outer_angle_deg": 20})"),
                "scene.json: lights[0].outer_angle_deg: 20 must be above "
                "lights[0].inner_angle_deg (30)");
    ExpectError(WithLights(spot + R"("inner_angle_deg": 30, "outer_angle_deg": 30})"),
                "scene.json: lights[0].outer_angle_deg: 30 must be above");
    ExpectError(WithLights(spot + R"("inner_angle_deg": 50})"),
                "scene.json: lights[0].inner_angle_deg: 50 must be below the default "
                "outer_angle_deg (45)");
    ExpectError(WithLights(spot + R"("outer_angle_deg": 20, "outer_cone_deg": 20})"),
                "scene.json: lights[0]: give outer_angle_deg or its older name outer_cone_deg, "
                "not both");
}

// Emission: two-sided, photometric luminance, and power spread over every shape using the
// material (pi L A from one face, 2 pi L A from two; a sphere's area 4 pi r^2).
TEST_F(SceneLoaderTest, PhotometricEmission) {
    const double pi = std::numbers::pi;
    const std::string quad = R"({"type": "quad", "material": "%", "vertices": [[0, 0, 0], )"
                             R"([0, 0, 2], [2, 0, 2], [2, 0, 0]]})";
    auto quad_of = [&](const std::string& material) {
        std::string q = quad;
        return q.replace(q.find('%'), 1, material);
    };
    absl::StatusOr<Scene> scene = Parse(SceneJson(
        quad_of("nits") + ", " + quad_of("one") + ", " + quad_of("one") + ", " + quad_of("two") +
            R"(, {"type": "sphere", "material": "ball", "center": [0, 0, 0], "radius": 0.5})",
        R"({"nits": {"type": "lambert", "reflectance": [0, 0, 0], "luminance_nits": 683,
                     "temperature_k": 4000},
            "one": {"type": "lambert", "reflectance": [0, 0, 0], "power_lm": 1000},
            "two": {"type": "lambert", "reflectance": [0, 0, 0], "power_lm": 1000,
                    "two_sided": true, "color": [1, 0, 0]},
            "ball": {"type": "principled", "power_lm": 1000},
            "panel": {"type": "lambert", "reflectance": [0, 0, 0], "emission": 3,
                      "color": [1, 0.5, 0.5], "two_sided": true}})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_TRUE(CapturedLog().str().empty()) << CapturedLog().str();
    const std::vector<Material>& m = scene->materials;
    ExpectRgbNear(m[0].emission, BlackbodyRgb(4000));
    EXPECT_FALSE(m[0].two_sided_emission);
    // Two quads of area 4 share "one": L = 1000 / (pi 8) cd/m^2.
    ExpectRgbNear(m[1].emission, Rgb(float(1000 / (pi * 8) / 683)));
    EXPECT_TRUE(m[2].two_sided_emission);
    ExpectRgbNear(m[2].emission, Rgb(float(1000 / (2 * pi * 4) / 683 / 0.2126), 0, 0));
    ExpectRgbNear(m[3].emission, Rgb(float(1000 / (pi * pi) / 683)));  // sphere area pi
    EXPECT_EQ(m[4].emission, Rgb(3, 1.5f, 1.5f));
    EXPECT_TRUE(m[4].two_sided_emission);
}

TEST_F(SceneLoaderTest, EmissionErrorsNameThePath) {
    Write("glow.png", lf::testing::PngBytes(1, 1, 3, {255, 255, 255}));
    const std::string lambert = R"({"type": "lambert", "reflectance": [1, 1, 1], )";
    ExpectError(WithMaterial(lambert + R"("power_lm": 100})"),
                "scene.json: materials.m.power_lm: no shape uses this material");
    ExpectError(WithMaterial(lambert + R"("emission": [1, 1, 1], "luminance_nits": 5})"),
                "scene.json: materials.m: give a radiometric strength (emission) or a photometric "
                "one (luminance_nits or power_lm), not both");
    ExpectError(WithMaterial(lambert + R"("luminance_nits": -1})"),
                "scene.json: materials.m.luminance_nits: must be ≥ 0");
    ExpectError(WithMaterial(lambert + R"("temperature_k": 3000})"),
                "scene.json: materials.m: color and temperature_k are the emission's colour");
    ExpectError(WithMaterial(lambert + R"("emission": [1, 1, 1], "temperature_k": 3000})"),
                "scene.json: materials.m.emission: an [r, g, b] strength is a colour itself");
    // Two-sided emission needs a back face rays can hit.
    ExpectError(WithMaterial(R"({"type": "principled", "double_sided": false, "two_sided": true, )"
                             R"("power_lm": 10})"),
                "scene.json: materials.m.two_sided: a single-sided surface (double_sided false) "
                "cannot be seen, so cannot emit, from behind");
    ExpectError(WithMaterial(lambert + R"("two_sided": 1, "emission": [1, 1, 1]})"),
                "scene.json: materials.m.two_sided: expected true or false, got number 1");
    ExpectError(WithMaterial(R"({"type": "principled", "emission_texture": "glow.png", )"
                             R"("power_lm": 10})"),
                "scene.json: materials.m.power_lm: cannot spread a power over an "
                "emission_texture");
}

TEST_F(SceneLoaderTest, EnvironmentLights) {
    // Top row white, bottom row black: the upper hemisphere is 1, the lower 0, so the map's
    // mean luminance over the sphere is 1/2.
    Write("sky.hdr", lf::testing::HdrBytes(4, 2, {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,  //
                                                  0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
    auto environment = [&](const std::string& sky) {
        absl::StatusOr<Scene> scene = Parse(WithLights(sky));
        EXPECT_TRUE(scene.ok()) << scene.status();
        EXPECT_TRUE(CapturedLog().str().empty()) << CapturedLog().str();
        return scene.ok() && scene->environment ? *scene->environment : EnvironmentLight{};
    };
    EXPECT_EQ(environment(R"({"type": "environment", "radiance": [1, 2, 3]})").radiance,
              Rgb(1, 2, 3));
    EXPECT_EQ(environment(R"({"type": "environment", "radiance": [1, 2, 3], "scale": 2})").radiance,
              Rgb(2, 4, 6));
    EXPECT_EQ(environment(R"({"type": "environment", "luminance_nits": 683})").radiance, Rgb(1));
    ExpectRgbNear(
        environment(R"({"type": "environment", "luminance_nits": 683, "temperature_k": 9000})")
            .radiance,
        BlackbodyRgb(9000));
    const EnvironmentLight map =
        environment(R"({"type": "environment", "file": "sky.hdr", "rotate_y_deg": 90})");
    ASSERT_NE(map.map, nullptr);
    EXPECT_EQ(map.map->width, 4);
    EXPECT_TRUE(map.map->hdr);
    EXPECT_EQ(map.radiance, Rgb(1));
    EXPECT_DOUBLE_EQ(map.rotate_y, std::numbers::pi / 2);
    EXPECT_EQ(environment(R"({"type": "environment", "file": "sky.hdr", "scale": 3, )"
                          R"("color": [1, 0.5, 0.5]})")
                  .radiance,
              Rgb(3, 1.5f, 1.5f));
    // Photometric with a map: its mean luminance (1/2) becomes 683 cd/m^2.
    EXPECT_EQ(environment(R"({"type": "environment", "file": "sky.hdr", "luminance_nits": 683})")
                  .radiance,
              Rgb(2));
}

// Texels the renderer does not emit (NaN, infinite, negative: lf::EmittableRadiance) do not
// count in the map's mean either, so luminance_nits sets the light that is actually emitted.
TEST_F(SceneLoaderTest, PhotometricSkyIgnoresTexelsThatEmitNothing) {
    // Top row 1, bottom row NaN, +inf, -5 and 0: as emitted, the half-lit map of mean 1/2.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    Image image(4, 2);
    for (const char* c : {"R", "G", "B"}) image.Channel(c) = {1, 1, 1, 1, nan, inf, -5, 0};
    ASSERT_TRUE(WriteExr((dir_ / "sky.exr").string(), image, {}).ok());
    const absl::StatusOr<Scene> scene =
        Parse(WithLights(R"({"type": "environment", "file": "sky.exr", "luminance_nits": 683})"));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_TRUE(scene->environment);
    EXPECT_EQ(scene->environment->radiance, Rgb(2));
}

// --sky (SceneOptions::sky): white, a colour, a grey or a map file read beside the scene, in
// place of the scene's environment with a warning; it counts in the content hash.
TEST_F(SceneLoaderTest, SkyOptionAddsOrReplacesTheEnvironment) {
    Write("sky.hdr", lf::testing::HdrBytes(2, 1, {4, 4, 4, 0, 0, 0}));
    Write("sky.png", lf::testing::PngBytes(2, 1, 3, {255, 255, 255, 0, 0, 0}));
    const auto with_sky = [&](const std::string& json, const std::string& sky) {
        return ParseScene(json, "scene.json", ReadBeside(dir_.string()), {.sky = sky});
    };
    const std::string bare = WithLights("");
    const absl::StatusOr<Scene> none = Parse(bare);
    ASSERT_TRUE(none.ok()) << none.status();
    EXPECT_FALSE(none->environment);
    for (const auto& [text, radiance] : {std::pair<std::string, Rgb>{"white", Rgb(1)},
                                         {"0.5", Rgb(0.5f)},
                                         {"1,2.5,0", Rgb(1, 2.5f, 0)}}) {
        CapturedLog().str("");
        const absl::StatusOr<Scene> scene = with_sky(bare, text);
        ASSERT_TRUE(scene.ok()) << text << ": " << scene.status();
        ASSERT_TRUE(scene->environment) << text;
        EXPECT_EQ(scene->environment->radiance, radiance) << text;
        EXPECT_EQ(scene->environment->map, nullptr) << text;
        EXPECT_NE(scene->content_hash, none->content_hash) << text;
        EXPECT_EQ(CapturedLog().str().find("--sky"), std::string::npos) << CapturedLog().str();
    }
    EXPECT_NE(with_sky(bare, "white")->content_hash, with_sky(bare, "0.5")->content_hash);
    const absl::StatusOr<Scene> map = with_sky(bare, "sky.hdr");
    ASSERT_TRUE(map.ok()) << map.status();
    ASSERT_TRUE(map->environment && map->environment->map);
    EXPECT_EQ(map->environment->map->width, 2);
    EXPECT_EQ(map->environment->radiance, Rgb(1));
    // Replacing the scene's own sky says so.
    CapturedLog().str("");
    const absl::StatusOr<Scene> replaced =
        with_sky(WithLights(R"({"type": "environment", "radiance": [3, 3, 3]})"), "white");
    ASSERT_TRUE(replaced.ok()) << replaced.status();
    EXPECT_EQ(replaced->environment->radiance, Rgb(1));
    EXPECT_NE(CapturedLog().str().find("scene.json: --sky replaces the scene's environment light"),
              std::string::npos)
        << CapturedLog().str();
    // Bad values name the flag and the value.
    for (const auto& [text, expected, code] :
         {std::tuple<std::string, std::string, absl::StatusCode>{
              "1,2", "--sky \"1,2\": 2 numbers; expected white, R,G,B or a number",
              absl::StatusCode::kInvalidArgument},
          {"-1", "--sky \"-1\": \"-1\" is not a radiance", absl::StatusCode::kInvalidArgument},
          {"1,1,1e11", "--sky \"1,1,1e11\": \"1e11\" is not a radiance",
           absl::StatusCode::kInvalidArgument},
          {"nope.hdr", "scene.json: --sky \"nope.hdr\": ", absl::StatusCode::kNotFound},
          {"sky.png",
           "scene.json: --sky: \"sky.png\" is an 8- or 16-bit image of display values, not "
           "radiance",
           absl::StatusCode::kInvalidArgument}}) {
        const absl::StatusOr<Scene> scene = with_sky(bare, text);
        ASSERT_FALSE(scene.ok()) << text;
        EXPECT_EQ(scene.status().code(), code) << scene.status();
        EXPECT_NE(scene.status().message().find(expected), std::string::npos)
            << "message: " << scene.status().message() << "\nexpected: " << expected;
    }
}

TEST_F(SceneLoaderTest, EnvironmentErrorsNameThePath) {
    Write("sky.png", lf::testing::PngBytes(2, 1, 3, {255, 255, 255, 0, 0, 0}));
    Write("black.hdr", lf::testing::HdrBytes(2, 1, {0, 0, 0, 0, 0, 0}));
    Write("bad.hdr", "#?RADIANCE\nnot an image");
    ExpectError(WithLights(R"({"type": "environment", "file": "nope.hdr"})"),
                "scene.json: lights[0].file \"nope.hdr\": ", absl::StatusCode::kNotFound);
    ExpectError(WithLights(R"({"type": "environment", "file": "bad.hdr"})"),
                "scene.json: lights[0].file: ");
    ExpectError(WithLights(R"({"type": "environment", "file": "sky.png"})"),
                "scene.json: lights[0].file: \"sky.png\" is an 8- or 16-bit image of display "
                "values, not radiance");
    ExpectError(WithLights(R"({"type": "environment", "file": "black.hdr", "luminance_nits": 1})"),
                "scene.json: lights[0].file: \"black.hdr\" is black");
    ExpectError(WithLights(R"({"type": "environment", "radiance": [1, 1, 1]}, )"
                           R"({"type": "environment", "radiance": [1, 1, 1]})"),
                "scene.json: lights[1]: a second environment light (the first is lights[0]): a "
                "scene has at most one sky");
    ExpectError(WithLights(R"({"type": "environment", "radiance": [1, 1, 1], "scale": -1})"),
                "scene.json: lights[0].scale: must be ≥ 0 and at most 1e10, got -1");
    ExpectError(WithLights(R"({"type": "environment", "radiance": 1e10, "scale": 2})"),
                "scene.json: lights[0]: too bright: the sky's radiance (or a map's factor) is over "
                "1e10");
    ExpectError(WithLights(R"({"type": "environment", "luminance_nits": -2})"),
                "scene.json: lights[0].luminance_nits: must be ≥ 0");
    ExpectError(WithLights(R"({"type": "environment", "luminance_nits": 2, "scale": 2})"),
                "scene.json: lights[0].scale: luminance_nits sets the sky's strength already");
    ExpectError(WithLights(R"({"type": "environment", "radiance": [1, 1, 1], "file": "sky.hdr"})"),
                "scene.json: lights[0].radiance: a uniform sky's radiance; with a file");
    ExpectError(WithLights(R"({"type": "environment"})"),
                "scene.json: lights[0]: give exactly one of radiance (W m^-2 sr^-1) or "
                "luminance_nits (cd/m^2)");
}

// The sky file is read through the scene's reader, as meshes and textures are, so `submit`
// (which uploads exactly what that reader was asked for) uploads it, and it counts in the
// content hash.
TEST_F(SceneLoaderTest, SkyFileIsReadThroughTheSceneReader) {
    Write("sky.hdr", lf::testing::HdrBytes(1, 1, {1, 1, 1}));
    std::vector<std::string> read;
    const SceneFileReader beside = ReadBeside(dir_.string());
    const SceneFileReader recording = [&](const std::string& name) {
        read.push_back(name);
        return beside(name);
    };
    const std::string json = SceneJson(
        kQuad, kMaterials, kCamera, R"(, "lights": [{"type": "environment", "file": "sky.hdr"}])");
    const absl::StatusOr<Scene> scene = ParseScene(json, "scene.json", recording);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(read, std::vector<std::string>{"sky.hdr"});
    Write("sky.hdr", lf::testing::HdrBytes(1, 1, {2, 2, 2}));
    const absl::StatusOr<Scene> changed = Parse(json);
    ASSERT_TRUE(changed.ok()) << changed.status();
    EXPECT_NE(changed->content_hash, scene->content_hash);
}

TEST_F(SceneLoaderTest, CameraFilterAndTheFilterOption) {
    auto with_filter = [](const std::string& filter) {
        return SceneJson(kQuad, kMaterials,
                         R"({"position": [0, 0, -5], "look_at": [0, 0, 0], "fov_y_deg": 40, )"
                         R"("resolution": [8, 8], "filter": )" +
                             filter + "}");
    };
    auto filter_of = [&](const std::string& filter) {
        absl::StatusOr<Scene> scene = Parse(with_filter(filter));
        EXPECT_TRUE(scene.ok()) << scene.status();
        return scene.ok() ? scene->camera.filter : PixelFilter{};
    };
    const PixelFilter gaussian = filter_of(R"({"type": "gaussian", "width": 2})");
    EXPECT_EQ(gaussian.type, PixelFilter::Type::kGaussian);
    EXPECT_EQ(gaussian.width, 2);
    const PixelFilter blackman_harris = filter_of(R"({"type": "blackman-harris"})");
    EXPECT_EQ(blackman_harris.type, PixelFilter::Type::kBlackmanHarris);
    EXPECT_EQ(blackman_harris.width, 3);
    EXPECT_EQ(filter_of(R"({"type": "box"})").width, 1);
    EXPECT_EQ(Parse(SceneJson(kQuad))->camera.filter.type, PixelFilter::Type::kBox);

    ExpectError(with_filter(R"({"type": "mitchell"})"),
                "scene.json: camera.filter.type: unknown filter type \"mitchell\"; expected box, "
                "gaussian or blackman-harris");
    ExpectError(with_filter(R"({"type": "gaussian", "width": 40})"),
                "scene.json: camera.filter.width: width 40: expected 0.5 to 16 pixels");
    ExpectError(with_filter(R"({"type": "box", "width": 2})"),
                "scene.json: camera.filter.width: width 2: the box filter is one pixel wide");
    ExpectError(with_filter(R"("gaussian")"), "scene.json: camera.filter: expected an object");

    // --filter replaces the scene's, a JSON camera's and a glTF camera's alike.
    const PixelFilter option{PixelFilter::Type::kBlackmanHarris, 1.5};
    const absl::StatusOr<Scene> json =
        ParseScene(with_filter(R"({"type": "gaussian", "width": 2})"), "scene.json",
                   ReadBeside(dir_.string()), {.filter = option});
    ASSERT_TRUE(json.ok()) << json.status();
    EXPECT_EQ(json->camera.filter.type, option.type);
    EXPECT_EQ(json->camera.filter.width, 1.5);
    Write("tex.png", lf::testing::PngBytes(2, 2, 4, lf::testing::TestTexels()));
    const absl::StatusOr<Scene> gltf = ParseScene(lf::testing::TexturedTestScene().Glb(), "s.glb",
                                                  ReadBeside(dir_.string()), {.filter = option});
    ASSERT_TRUE(gltf.ok()) << gltf.status();
    EXPECT_EQ(gltf->camera.filter.type, option.type);
    const absl::StatusOr<Scene> bad =
        ParseScene(SceneJson(kQuad), "scene.json", ReadBeside(dir_.string()),
                   {.filter = PixelFilter{PixelFilter::Type::kGaussian, 0.1}});
    EXPECT_EQ(bad.status().message(),
              "scene.json: --filter gaussian: width 0.1: expected 0.5 to 16 pixels");
}

// glTF spots keep KHR_lights_punctual's falloff, JSON spots get pbrt-v4's smoothstep.
TEST_F(SceneLoaderTest, GltfSpotsKeepTheirFalloff) {
    lf::testing::GltfBuilder b = lf::testing::TexturedTestScene();
    b.json()["extensions"]["KHR_lights_punctual"]["lights"].push_back(
        {{"type", "spot"}, {"intensity", 683}, {"spot", {{"outerConeAngle", 0.4}}}});
    b.json()["scenes"][0]["nodes"].push_back(
        b.AddNode({{"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}}));
    Write("tex.png", lf::testing::PngBytes(2, 2, 4, lf::testing::TestTexels()));
    const absl::StatusOr<Scene> scene = ParseScene(b.Glb(), "s.glb", ReadBeside(dir_.string()));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_EQ(scene->spot_lights.size(), 1u);
    EXPECT_EQ(scene->spot_lights[0].falloff, SpotLight::Falloff::kKhrLightsPunctual);
    // Its colour is glTF's, not normalised: KHR_lights_punctual's candela are of `color` as is.
    EXPECT_EQ(scene->point_lights[0].intensity, Rgb(10, 5, 2.5f));
}

}  // namespace
}  // namespace lf
