#include "lf/core/scene_loader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "scene_log.h"
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

class SceneLoaderTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_scene_loader");
        CapturedLog().str("");
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    void Write(const std::string& name, const std::string& bytes) {
        std::ofstream(dir_ / name, std::ios::binary) << bytes;
    }

    absl::StatusOr<Scene> Parse(const std::string& json) {
        return ParseScene(json, "scene.json", ReadBeside(dir_.string()));
    }

    // Parsing must fail with a message containing `expected`.
    void ExpectError(const std::string& json, const std::string& expected,
                     absl::StatusCode code = absl::StatusCode::kInvalidArgument) {
        absl::StatusOr<Scene> scene = Parse(json);
        ASSERT_FALSE(scene.ok()) << "expected an error containing: " << expected;
        EXPECT_EQ(scene.status().code(), code) << scene.status();
        EXPECT_NE(scene.status().message().find(expected), std::string::npos)
            << "message: " << scene.status().message() << "\nexpected: " << expected;
    }

    std::filesystem::path dir_;
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
    EXPECT_NE(CapturedLog().str().find("no emissive shape and no point light"), std::string::npos);
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
                          R"(, "lights": [{"type": "spot", "position": [0, 0, 0]}])"),
                "scene.json: lights[0].type: unknown light type \"spot\"");
    ExpectError(
        SceneJson(kQuad, kMaterials, kCamera,
                  R"(, "lights": [{"type": "point", "position": [0, 0, 0], "power": [1, 1, 1], )"
                  R"("intensity": [1, 1, 1]}])"),
        "scene.json: lights[0]: give exactly one of intensity (W/sr) or power (W)");
}

TEST_F(SceneLoaderTest, MaterialErrorsNameThePath) {
    auto with_material = [](const std::string& material) {
        return SceneJson(
            kQuad, R"({"lamp": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [1, 1, 1]},
                                   "m": )" +
                       material + "}");
    };
    ExpectError(with_material(R"({"type": "metal"})"),
                "scene.json: materials.m.type: unknown material type \"metal\"");
    ExpectError(with_material(R"({"type": "lambert"})"),
                "scene.json: materials.m: missing required key \"reflectance\"");
    ExpectError(with_material(R"({"type": "mirror", "reflectance": [1, 1.5, 1]})"),
                "scene.json: materials.m.reflectance[1]: must be in [0, 1], got 1.5");
    ExpectError(
        with_material(R"({"type": "lambert", "reflectance": [1, 1, 1], "emission": [-1, 0, 0]})"),
        "scene.json: materials.m.emission[0]: must be ≥ 0");
    // Absurdly bright: the light sampler's power would overflow and the film would clamp.
    ExpectError(
        with_material(R"({"type": "lambert", "reflectance": [1, 1, 1], "emission": [1, 3e38, 0]})"),
        "scene.json: materials.m.emission[1]: must be ≥ 0 and at most 1e+10, got 3e+38");
    ExpectError(with_material(R"({"type": "glossy", "roughness": 0, "reflectance": [1, 1, 1]})"),
                "scene.json: materials.m.roughness: must be a positive float, got 0");
    ExpectError(with_material(R"({"type": "glossy", "roughness": 0.1, "distribution": "phong", )"
                              R"("reflectance": [1, 1, 1]})"),
                "scene.json: materials.m.distribution: unknown distribution \"phong\"");
    ExpectError(with_material(R"({"type": "glossy", "roughness": 0.1, "reflectance": [1, 1, 1], )"
                              R"("eta": [1, 1, 1], "k": [0, 0, 0]})"),
                "scene.json: materials.m: give either reflectance or eta and k, not both");
    ExpectError(with_material(R"({"type": "glossy", "roughness": 0.1, "eta": [1, 1, 1]})"),
                "scene.json: materials.m: missing required key \"k\"");
    ExpectError(with_material(R"({"type": "dielectric", "ior": -1.5})"),
                "scene.json: materials.m.ior: must be a positive float");
    ExpectError(with_material("[]"), "scene.json: materials.m: expected an object, got array");
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

}  // namespace
}  // namespace lf
