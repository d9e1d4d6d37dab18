// Meshing for radiosity: the barycentric subdivision and its point location, shared vertices,
// the patch-count target, and which patch sides get unknowns.
#include "lf/core/patch_mesh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "lf/core/scene_loader.h"
#include "test_scenes.h"

namespace lf {
namespace {

Scene OneTriangle() {
    Scene scene;
    Material m;
    m.emission = Rgb(1.0f);
    scene.materials.push_back(m);
    TriangleMesh t;
    t.positions = {{0, 0, 0}, {3, 0, 0}, {0.5, 2, 0}};
    t.triangles = {{0, 1, 2}};
    scene.meshes.push_back(t);
    return scene;
}

TEST(PatchMesh, SubdividesBarycentricallyAndLocatesPoints) {
    const Scene scene = OneTriangle();
    PatchMeshOptions options;
    options.patch_size = 0.81;  // longest edge 3.2: k = 4
    auto mesh = PatchMesh::Build(scene, options);
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    EXPECT_EQ(mesh->Subdivision(0, 0), 4);
    EXPECT_EQ(mesh->patches().size(), 16u);
    EXPECT_EQ(mesh->vertices().size(), 15u);  // (k+1)(k+2)/2 grid vertices
    double area = 0;
    for (const auto& p : mesh->patches()) area += p.area;
    EXPECT_NEAR(area, 3.0, 1e-12);

    // Every point maps to a patch whose barycentric weights are non-negative and give the
    // point back; grid points and edges included.
    for (int i = 0; i <= 40; ++i) {
        for (int j = 0; i + j <= 40; ++j) {
            const double b1 = i / 40.0, b2 = j / 40.0;
            const PatchPoint point = mesh->Locate(0, 0, b1, b2);
            ASSERT_GE(point.patch, 0);
            ASSERT_LT(point.patch, 16);
            for (double w : point.w) EXPECT_GE(w, 0);
            const auto back = mesh->TriangleBarycentrics(point.patch, point.w);
            EXPECT_NEAR(back[0], b1, 1e-12);
            EXPECT_NEAR(back[1], b2, 1e-12);
            // ... and the patch's own corners, in world space, surround it.
            const auto& patch = mesh->patches()[size_t(point.patch)];
            Vec3d x;
            for (int c = 0; c < 3; ++c)
                x += mesh->vertices()[patch.vertices[size_t(c)]] * point.w[size_t(c)];
            const Vec3d expected = Vec3d(3, 0, 0) * b1 + Vec3d(0.5, 2, 0) * b2;
            EXPECT_NEAR(Length(x - expected), 0, 1e-12);
        }
    }
}

TEST(PatchMesh, QuadHalvesShareTheirDiagonal) {
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    PatchMeshOptions options;
    options.patch_size = 2 * std::sqrt(2.0) / 4.99;  // just over a face diagonal / 5: k = 5
    auto mesh = PatchMesh::Build(scene, options);
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    EXPECT_EQ(mesh->patches().size(), 6u * 2 * 25);
    EXPECT_EQ(mesh->vertices().size(), 6u * 36);  // (k+1)^2 per face, faces are separate meshes
}

TEST(PatchMesh, TargetCountIsTheCoarsestFit) {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    for (int64_t target : {100, 1000, 4000}) {
        PatchMeshOptions options;
        options.patches = target;
        auto mesh = PatchMesh::Build(*scene, options);
        ASSERT_TRUE(mesh.ok()) << mesh.status();
        EXPECT_LE(int64_t(mesh->patches().size()), target);
        PatchMeshOptions finer;
        finer.patch_size = mesh->patch_size() * (1 - 1e-9);
        EXPECT_GT(int64_t(PatchMesh::Build(*scene, finer)->patches().size()), target);
    }
}

int CountBackSides(const PatchMesh& mesh) {
    int back = 0;
    for (const auto& s : mesh.sides()) back += s.back;
    return back;
}

TEST(PatchMesh, SidesExistOnlyWhereRadiosityCanBeNonZero) {
    // A closed box: only the inward sides.
    const Scene box = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    auto mesh = PatchMesh::Build(box, {});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    EXPECT_EQ(mesh->sides().size(), mesh->patches().size());
    EXPECT_EQ(CountBackSides(*mesh), 0);
    for (const auto& p : mesh->patches()) EXPECT_GE(p.sides[0], 0);

    // A lone emitter: its front emits, nothing lights its back.
    Scene lone = OneTriangle();
    EXPECT_EQ(PatchMesh::Build(lone, {})->sides().size(),
              PatchMesh::Build(lone, {})->patches().size());
    // Black and not emitting: nothing to solve for.
    lone.materials[0].emission = Rgb(0);
    lone.materials[0].reflectance = Rgb(0);
    EXPECT_TRUE(PatchMesh::Build(lone, {})->sides().empty());
    // Reflective, lit from both sides by point lights: both sides.
    lone.materials[0].reflectance = Rgb(0.5f);
    lone.point_lights = {{Vec3d(1, 1, 1), Rgb(1)}, {Vec3d(1, 1, -1), Rgb(1)}};
    auto both = PatchMesh::Build(lone, {});
    EXPECT_EQ(both->sides().size(), 2 * both->patches().size());
    // Sides run front before back within a mesh.
    EXPECT_FALSE(both->sides().front().back);
    EXPECT_TRUE(both->sides().back().back);
}

TEST(PatchMesh, CornellBoxSides) {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    auto mesh = PatchMesh::Build(*scene, {});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    for (const auto& p : mesh->patches()) {
        const std::string& name = scene->meshes[size_t(p.mesh)].name;
        EXPECT_GE(p.sides[0], 0) << name;
        // Walls have nothing behind them, the light's back is black; the blocks' faces see
        // into the blocks' closed interiors (which stay dark).
        const bool block = name.rfind("short", 0) == 0 || name.rfind("tall", 0) == 0;
        EXPECT_EQ(p.sides[1] >= 0, block) << name;
    }
}

TEST(PatchMesh, RefusesWhatRadiosityCannotModel) {
    Scene scene = OneTriangle();
    scene.spheres.push_back({"ball", 0, Vec3d(), 1});
    EXPECT_EQ(PatchMesh::Build(scene, {}).status().code(), absl::StatusCode::kInvalidArgument);
    scene = OneTriangle();
    scene.materials[0].type = Material::Type::kMirror;
    auto mirror = PatchMesh::Build(scene, {});
    EXPECT_EQ(mirror.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(mirror.status().message().find("mirror"), std::string::npos);
    PatchMeshOptions none;
    none.patches = 0;
    EXPECT_EQ(PatchMesh::Build(OneTriangle(), none).status().code(),
              absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
