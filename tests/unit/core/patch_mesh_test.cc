// Meshing for radiosity: the barycentric subdivision and its point location, shared vertices,
// the patch-count target, and which patch sides get unknowns.
#include "lf/core/patch_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

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

// A target count above the mesher's limit once sent the size search into an endless loop:
// every count it tried stayed at or under the target. Any target and any size now ends, with an
// error or a mesh within the limits.
TEST(PatchMesh, SearchEndsForAnyTargetOrSize) {
    const Scene scene = OneTriangle();
    PatchMeshOptions huge_target;
    huge_target.patches = int64_t(1) << 40;
    auto refused = PatchMesh::Build(scene, huge_target);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(refused.status().message().find("1099511627776 patches"), std::string::npos)
        << refused.status();

    PatchMeshOptions tiny;
    tiny.patches = int64_t(1) << 40;  // ignored: the size decides
    tiny.patch_size = 1e-300;
    EXPECT_EQ(PatchMesh::Build(scene, tiny).status().code(), absl::StatusCode::kInvalidArgument);

    PatchMeshOptions huge;
    huge.patch_size = 1e300;
    auto one = PatchMesh::Build(scene, huge);
    ASSERT_TRUE(one.ok()) << one.status();
    EXPECT_EQ(one->patches().size(), 1u);

    for (double bad : {std::nan(""), double(INFINITY), -1.0}) {
        PatchMeshOptions options;
        options.patch_size = bad;
        EXPECT_EQ(PatchMesh::Build(scene, options).status().code(),
                  absl::StatusCode::kInvalidArgument)
            << bad;
    }

    // Every edge degenerate: no size gives more patches than triangles.
    Scene flat = OneTriangle();
    flat.meshes[0].positions = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
    PatchMeshOptions many;
    many.patches = 1000;
    auto degenerate = PatchMesh::Build(flat, many);
    if (degenerate.ok()) {
        EXPECT_EQ(degenerate->patches().size(), 1u);
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
    // Black and not emitting, with nothing in front: nothing to solve for.
    lone.materials[0].emission = Rgb(0);
    lone.materials[0].reflectance = Rgb(0);
    EXPECT_TRUE(PatchMesh::Build(lone, {})->sides().empty());
    // Black and lit: a black side's radiosity is 0, but its irradiance is shown.
    lone.point_lights = {{Vec3d(1, 1, 1), Rgb(1)}};
    EXPECT_EQ(PatchMesh::Build(lone, {})->sides().size(),
              PatchMesh::Build(lone, {})->patches().size());
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
        // Walls have nothing behind them; the light's back is black but faces the ceiling,
        // whose light it receives (its illuminance); the blocks' faces see into the blocks'
        // closed interiors (which stay dark).
        const bool block = name.rfind("short", 0) == 0 || name.rfind("tall", 0) == 0;
        EXPECT_EQ(p.sides[1] >= 0, block || name == "light") << name;
    }
}

// A unit square as one quad, k = 4 on both halves.
Scene UnitQuad() {
    Scene scene = OneTriangle();
    scene.meshes[0].is_quad = true;
    scene.meshes[0].positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    scene.meshes[0].triangles = {{0, 1, 2}, {0, 2, 3}};
    return scene;
}

// Splits the patches whose centroid is within `radius` of `centre`, `levels` times over: a
// refinement around a point on the quad's diagonal, so both halves split alike there and T-
// junctions appear where the levels change.
PatchMeshOptions RefinedAround(const Scene& scene, const Vec3d& centre, double radius, int levels) {
    PatchMeshOptions options;
    options.patch_size = 0.26;  // longest edge sqrt(2): k = 6
    for (int level = 0; level < levels; ++level) {
        auto mesh = PatchMesh::Build(scene, options);
        EXPECT_TRUE(mesh.ok()) << mesh.status();
        for (int64_t p = 0; p < int64_t(mesh->patches().size()); ++p) {
            if (Length(mesh->Centroid(p) - centre) < radius) {
                options.split.push_back(mesh->Cell(p));
            }
        }
    }
    return options;
}

double GeometricArea(const PatchMesh& mesh, const PatchMesh::Patch& p) {
    const Vec3d &a = mesh.vertices()[p.vertices[0]], &b = mesh.vertices()[p.vertices[1]],
                &c = mesh.vertices()[p.vertices[2]];
    return 0.5 * Length(Cross(b - a, c - a));
}

TEST(PatchMesh, SplitCellsTileTheirParentsAndShareVertices) {
    const Scene scene = UnitQuad();
    const PatchMeshOptions options = RefinedAround(scene, Vec3d(0.4, 0.4, 0), 0.2, 3);
    auto mesh = PatchMesh::Build(scene, options);
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    const int64_t splits = int64_t(mesh->split().size());
    EXPECT_EQ(int64_t(mesh->patches().size()), 2 * 36 + 3 * splits);
    int deepest = 0;
    double area = 0;
    for (const auto& p : mesh->patches()) {
        deepest = std::max(deepest, p.level);
        // Each patch's corners are its cell's: the stated area (coarse area / 4^level) is the
        // triangle's.
        EXPECT_NEAR(GeometricArea(*mesh, p), p.area, 1e-15);
        EXPECT_EQ(p.area, 0.5 / 36 / double(1 << (2 * p.level)));
        area += p.area;
    }
    EXPECT_EQ(deepest, 3);
    EXPECT_NEAR(area, 1.0, 1e-12);
    // Not a global refinement: cells far from the centre stay coarse.
    EXPECT_EQ(mesh->Locate(0, 0, 0.95, 0.01).patch, mesh->Locate(0, 0, 0.97, 0.02).patch);
    EXPECT_EQ(mesh->patches()[size_t(mesh->Locate(0, 0, 0.95, 0.01).patch)].level, 0);

    // Every point lands in a patch of its triangle whose corners give it back with weights in
    // [0, 1]: with the areas summing to the whole, the patches tile it without overlap.
    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(0, 1);
    for (int n = 0; n < 20000; ++n) {
        double b1 = u(rng), b2 = u(rng);
        if (b1 + b2 > 1) std::tie(b1, b2) = std::pair(1 - b1, 1 - b2);
        const int primitive = n % 2;
        const PatchPoint point = mesh->Locate(0, primitive, b1, b2);
        const auto& patch = mesh->patches()[size_t(point.patch)];
        ASSERT_EQ(patch.primitive, primitive);
        Vec3d x;
        for (size_t c = 0; c < 3; ++c) {
            ASSERT_GE(point.w[c], 0);
            x += mesh->vertices()[patch.vertices[c]] * point.w[c];
        }
        const auto& t = scene.meshes[0].triangles[size_t(primitive)];
        const auto& v = scene.meshes[0].positions;
        const Vec3d expected = v[t[0]] * (1 - b1 - b2) + v[t[1]] * b1 + v[t[2]] * b2;
        ASSERT_NEAR(Length(x - expected), 0, 1e-12) << b1 << " " << b2;
        const auto back = mesh->TriangleBarycentrics(point.patch, point.w);
        ASSERT_NEAR(back[0], b1, 1e-12);
        ASSERT_NEAR(back[1], b2, 1e-12);
    }

    // Coincident corners are one vertex: within a triangle, across the diagonal where both
    // halves split alike, and between levels (a corner of a quarter that is a corner of the
    // cell).
    std::set<uint32_t> used;
    for (const auto& p : mesh->patches()) used.insert(p.vertices.begin(), p.vertices.end());
    EXPECT_EQ(used.size(), mesh->vertices().size());
    // (Rounded: positions computed by other formulas may differ in the last bits.)
    std::set<std::pair<int64_t, int64_t>> positions;
    for (uint32_t v : used) {
        positions.insert(
            {std::llround(mesh->vertices()[v].x * 1e9), std::llround(mesh->vertices()[v].y * 1e9)});
    }
    EXPECT_EQ(positions.size(), used.size());

    // The split list builds the same mesh again.
    PatchMeshOptions again;
    again.patch_size = options.patch_size;
    again.split = mesh->split();
    auto rebuilt = PatchMesh::Build(scene, again);
    ASSERT_TRUE(rebuilt.ok()) << rebuilt.status();
    ASSERT_EQ(rebuilt->patches().size(), mesh->patches().size());
    for (size_t p = 0; p < mesh->patches().size(); ++p) {
        EXPECT_EQ(rebuilt->patches()[p].vertices, mesh->patches()[p].vertices);
    }
}

// Splitting cells of the second triangle leaves the first one's patches, vertices and sides as
// the unsplit mesh has them; without splits every patch is a level-0 cell in grid order.
TEST(PatchMesh, UnsplitTrianglesAreMeshedAsWithoutRefinement) {
    const Scene scene = UnitQuad();
    PatchMeshOptions options;
    options.patch_size = 0.26;
    auto plain = PatchMesh::Build(scene, options);
    ASSERT_TRUE(plain.ok()) << plain.status();
    EXPECT_TRUE(plain->split().empty());
    for (int64_t p = 0; p < int64_t(plain->patches().size()); ++p) {
        const PatchCell cell = plain->Cell(p);
        EXPECT_EQ(cell.level, 0);
        EXPECT_EQ(plain
                      ->Locate(0, cell.primitive, (cell.i + (cell.up ? 0.3 : 0.7)) / 6.0,
                               (cell.j + (cell.up ? 0.3 : 0.7)) / 6.0)
                      .patch,
                  p);
    }
    options.split = {{0, 1, 0, 2, 2, true}, {0, 1, 0, 0, 0, false}};
    auto split = PatchMesh::Build(scene, options);
    ASSERT_TRUE(split.ok()) << split.status();
    EXPECT_EQ(split->patches().size(), plain->patches().size() + 6);
    for (size_t p = 0; p < 36; ++p) {
        EXPECT_EQ(split->patches()[p].vertices, plain->patches()[p].vertices);
        EXPECT_EQ(split->patches()[p].area, plain->patches()[p].area);
        EXPECT_EQ(split->patches()[p].sides, plain->patches()[p].sides);
    }
    for (size_t v = 0; v < plain->vertices().size(); ++v) {
        EXPECT_EQ(split->vertices()[v], plain->vertices()[v]);
    }
}

TEST(PatchMesh, RefusesSplitsOutsideTheMesh) {
    const Scene scene = UnitQuad();
    for (const PatchCell& bad : {PatchCell{0, 0, 0, 6, 0, true},  // beyond the grid
                                 PatchCell{0, 2, 0, 0, 0, true},  // no such triangle
                                 PatchCell{0, 0, 1, 0, 0, true},  // parent not split
                                 PatchCell{0, 0, kMaxPatchLevel, 0, 0, true}}) {
        PatchMeshOptions options;
        options.patch_size = 0.26;
        options.split = {bad};
        EXPECT_EQ(PatchMesh::Build(scene, options).status().code(),
                  absl::StatusCode::kInvalidArgument)
            << bad.level << " " << bad.i;
    }
}

TEST(PatchMesh, RefusesWhatRadiosityCannotModel) {
    // A sphere is meshed before (TessellateSpheres); one left over is refused, by name.
    Scene scene = OneTriangle();
    scene.spheres.push_back({"ball", 0, Vec3d(), 1});
    auto sphere = PatchMesh::Build(scene, {});
    EXPECT_EQ(sphere.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(sphere.status().message().find("sphere \"ball\" was not meshed"), std::string::npos);
    scene = OneTriangle();
    scene.materials[0].type = Material::Type::kInterface;
    auto interface = PatchMesh::Build(scene, {});
    EXPECT_EQ(interface.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(interface.status().message().find("medium interface"), std::string::npos);
    PatchMeshOptions none;
    none.patches = 0;
    EXPECT_EQ(PatchMesh::Build(OneTriangle(), none).status().code(),
              absl::StatusCode::kInvalidArgument);
}

// What radiosity cannot model, with the reason `--method auto` logs and radiosity refuses with;
// what it takes from modelling tools (principled materials, textures, every light) is accepted.
TEST(PatchMesh, RadiosityLimitationSaysWhy) {
    auto why = [](void (*change)(Scene&)) {
        Scene scene = OneTriangle();
        scene.materials[0].name = "wood";
        scene.meshes[0].name = "floor";
        change(scene);
        return RadiosityLimitation(scene);
    };
    EXPECT_EQ(why([](Scene&) {}), "");
    EXPECT_EQ(why([](Scene& s) { s.materials[0].type = Material::Type::kPrincipled; }), "");
    EXPECT_EQ(why([](Scene& s) { s.materials[0].type = Material::Type::kMirror; }), "");
    EXPECT_EQ(why([](Scene& s) {
                  auto image = std::make_shared<TextureImage>();
                  image->name = "wood.png";
                  s.textures.push_back(image);
                  s.materials[0].base_color_texture.image = 0;
              }),
              "");
    EXPECT_EQ(why([](Scene& s) { s.spot_lights.emplace_back(); }), "");
    EXPECT_EQ(why([](Scene& s) {
                  s.directional_lights.push_back({Vec3d(0, -1, 0), Rgb(1.0f), 0.01});
              }),
              "");
    EXPECT_EQ(why([](Scene& s) { s.environment.emplace(); }), "");
    EXPECT_EQ(why([](Scene& s) { s.materials[0].type = Material::Type::kInterface; }),
              "material \"wood\" (mesh \"floor\") is a medium interface, which radiosity does "
              "not model");
    EXPECT_EQ(why([](Scene& s) { s.materials[0].alpha_mode = Material::AlphaMode::kMask; }),
              "material \"wood\" (mesh \"floor\") has an alpha mask, which radiosity does not "
              "model");
    EXPECT_EQ(why([](Scene& s) { s.materials[0].double_sided = false; }),
              "material \"wood\" (mesh \"floor\") is single-sided, which radiosity does not "
              "model");
    // Spheres are meshed (TessellateSpheres); their materials count like a mesh's.
    EXPECT_EQ(why([](Scene& s) { s.spheres.push_back({"ball", 0, Vec3d(), 1}); }), "");
    EXPECT_EQ(why([](Scene& s) {
                  s.spheres.push_back({"ball", 1, Vec3d(), 1});
                  s.materials.emplace_back().name = "glass";
                  s.materials.back().double_sided = false;
              }),
              "material \"glass\" (sphere \"ball\") is single-sided, which radiosity does not "
              "model");
    // Two-sided emission is modelled: both sides of an emitter's patches get unknowns.
    EXPECT_EQ(why([](Scene& s) { s.materials[0].two_sided_emission = true; }), "");
    // A material no shape uses does not matter.
    EXPECT_EQ(why([](Scene& s) { s.materials.emplace_back().type = Material::Type::kInterface; }),
              "");
    Scene masked = OneTriangle();
    masked.materials[0].alpha_mode = Material::AlphaMode::kBlend;
    EXPECT_EQ(PatchMesh::Build(masked, {}).status().message(),
              "radiosity: material \"\" (mesh \"\") is alpha-blended, which radiosity does not "
              "model; render it with --method path");
}

// What radiosity leaves out, by kind, each used material named once.
TEST(PatchMesh, RadiosityDropsNamesASpheresMaterial) {
    Scene scene = OneTriangle();
    Material& chrome = scene.materials.emplace_back();
    chrome.name = "chrome";
    chrome.type = Material::Type::kMirror;
    scene.spheres.push_back({"ball", 1, Vec3d(), 1});
    EXPECT_EQ(RadiosityDrops(scene), "no diffuse part (rendered black): \"chrome\" (mirror)");
}

TEST(PatchMesh, RadiosityDropsNamesWhatItLeavesOut) {
    Scene scene = OneTriangle();
    EXPECT_EQ(RadiosityDrops(scene), "");
    scene.materials[0].name = "plastic";
    scene.materials[0].type = Material::Type::kPrincipled;
    scene.materials[0].clearcoat = 0.5f;
    for (const auto& [name, type] : {std::pair{"glass", Material::Type::kDielectric},
                                     {"chrome", Material::Type::kMirror},
                                     {"unused", Material::Type::kGlossy}}) {
        Material& m = scene.materials.emplace_back();
        m.name = name;
        m.type = type;
    }
    Material& velvet = scene.materials.emplace_back();
    velvet.name = "velvet";
    velvet.type = Material::Type::kPrincipled;
    velvet.specular = 0;
    velvet.sheen_color = Rgb(0.5f);
    velvet.normal_texture.image = 0;
    for (int m : {1, 2, 0, 4, 1}) {
        scene.meshes.push_back(scene.meshes[0]);
        scene.meshes.back().material = m;
    }
    EXPECT_EQ(RadiosityDrops(scene),
              "no diffuse part (rendered black): \"glass\" (dielectric), \"chrome\" (mirror); "
              "specular reflection: \"plastic\"; clear coat: \"plastic\"; sheen: \"velvet\"; "
              "normal map: \"velvet\"");
    EXPECT_FALSE(MayReflectDiffusely(scene.materials[1]));
    EXPECT_TRUE(MayReflectDiffusely(scene.materials[0]));
    scene.materials[0].metallic = 1;
    EXPECT_FALSE(MayReflectDiffusely(scene.materials[0]));
    EXPECT_EQ(RadiosityDrops(scene).rfind(
                  "no diffuse part (rendered black): \"plastic\" (principled), \"glass\" "
                  "(dielectric)",
                  0),
              0u);
}

// A lone reflecting triangle gets unknowns only on the sides a light can reach: the side a
// spot, directional light or sun disk faces, both sides under a sky.
TEST(PatchMesh, LightsDecideWhichSidesGetUnknowns) {
    auto sides = [](void (*light)(Scene&)) {
        Scene scene = OneTriangle();  // in the plane z = 0, front normal +z
        scene.materials[0].emission = Rgb(0.0f);
        light(scene);
        auto mesh = PatchMesh::Build(scene, {.patches = 4});
        EXPECT_TRUE(mesh.ok()) << mesh.status();
        int front = 0, back = 0;
        for (const PatchMesh::Side& side : mesh->sides()) ++(side.back ? back : front);
        return std::pair{front, back};
    };
    EXPECT_EQ(sides([](Scene&) {}), std::pair(0, 0));
    const int n = sides([](Scene& s) { s.environment.emplace(); }).first;
    EXPECT_GT(n, 0);
    EXPECT_EQ(sides([](Scene& s) { s.environment.emplace(); }), std::pair(n, n));
    EXPECT_EQ(sides([](Scene& s) {
                  s.spot_lights.push_back({.position = {0, 0, 1}, .direction = {0, 0, -1}});
              }),
              std::pair(n, 0));
    EXPECT_EQ(sides([](Scene& s) {
                  s.directional_lights.push_back({Vec3d(0, 0, 1), Rgb(1.0f)});
              }),
              std::pair(0, n));
    // A sun disk 10° across, grazing at 2° below the plane from the back: its upper rim still
    // reaches the front.
    EXPECT_EQ(sides([](Scene& s) {
                  const double a = 2 * std::numbers::pi / 180;
                  s.directional_lights.push_back(
                      {Vec3d(std::cos(a), 0, std::sin(a)), Rgb(1.0f), 10 * std::numbers::pi / 180});
              }),
              std::pair(n, n));
}

}  // namespace
}  // namespace lf
