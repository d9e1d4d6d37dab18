// The radiosity facade: rendering a furnace through the tile renderer, point lights against
// their closed form, saving and loading solutions (and refusing mismatched ones), the PLY
// export, refusals of scenes radiosity cannot represent, and thread-count independence.
#include "lf/kernels/radiosity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/tile_renderer.h"
#include "local_executor.h"
#include "test_scenes.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

struct Prepared {
    std::unique_ptr<EmbreeScene> embree;
    absl::StatusOr<std::unique_ptr<RadiosityRenderer>> renderer;
};

// The scene must outlive the result (EmbreeScene keeps a reference).
Prepared Prepare(const Scene& scene, const RadiosityOptions& options) {
    Prepared p;
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    p.embree = std::move(*es);
    p.renderer = PrepareRadiosity(*p.embree, options);
    return p;
}

std::string TempPath(const std::string& name) {
    return (fs::temp_directory_path() /
            (name + "_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed())))
        .string();
}

// A furnace: every pixel is a convex combination of side values (flat shading picks one side,
// smooth interpolates area-weighted means), so it lies within their range; and their mean is
// within (r + ρε) / (1 - ρ(1 + ε)) of L_e / (1 - ρ), where r is the solver's residual and
// ε = 5e-3 the largest stated error of a form factor, which bounds every row's deviation from 1.
class RadiosityFurnace : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(RadiosityFurnace, RendersEmissionOverOneMinusRho) {
    const auto [half, offset] = GetParam();
    const float rho = 0.7f, le = 0.5f;
    const double epsilon = 5e-3;
    const Scene scene =
        testing::MakeFurnace(half, Vec3d(offset, 0.3 * offset, -offset), rho, le, 16);
    for (RadiosityShading shading : {RadiosityShading::kFlat, RadiosityShading::kSmooth}) {
        RadiosityOptions options;
        options.patches = 300;
        options.display = shading;
        Prepared p = Prepare(scene, options);
        ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
        const RadiosityRenderer& r = **p.renderer;
        double lo = 1e300, hi = 0, power = 0, area = 0;
        for (int32_t s = 0; s < int32_t(r.radiosity().size()); ++s) {
            const double a = r.mesh().patches()[size_t(r.mesh().sides()[size_t(s)].patch)].area;
            const double radiance = r.radiosity()[size_t(s)].r / kPi;
            lo = std::min(lo, radiance);
            hi = std::max(hi, radiance);
            power += a * radiance;
            area += a;
        }
        const double expected = le / (1 - rho);
        const double bound = (r.report().residual + rho * epsilon) / (1 - rho * (1 + epsilon));
        EXPECT_NEAR(power / area, expected, bound * expected);
        const Camera camera(scene.camera, p.embree->origin());
        RenderSettings settings;
        settings.spp = 2;
        const Image image = RenderImage(camera, r, settings).value().image;
        for (const char* channel : {"R", "G", "B"}) {
            for (float v : *image.FindChannel(channel)) {
                ASSERT_GE(v, lo * (1 - 1e-6));
                ASSERT_LE(v, hi * (1 + 1e-6));
            }
        }
    }
}

// Scale extremes and far from the origin: a leak or a false occlusion would show here.
INSTANTIATE_TEST_SUITE_P(Scales, RadiosityFurnace,
                         ::testing::Values(std::pair{1.0, 0.0}, std::pair{1e-4, 0.0},
                                           std::pair{1e5, 0.0}, std::pair{1.0, 1e5}));

// A point light at height h over a lambert floor: B = ρ I h / r^3, averaged over each patch.
// The reference averages 4096 midpoint samples per patch (error ~(1/64)^2 of the patch's
// variation); the solver uses the form factors' quadrature, whose stated error for separated
// pairs is 5e-4 (form_factors.h).
TEST(Radiosity, PointLightMatchesTheInverseSquareLaw) {
    Scene scene;
    Material floor;
    floor.reflectance = Rgb(0.6f, 0.5f, 0.4f);
    scene.materials.push_back(floor);
    TriangleMesh quad;
    quad.is_quad = true;
    quad.positions = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};  // normal +y
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(quad);
    const double h = 0.8;
    const Rgb intensity(2, 3, 4);
    scene.point_lights.push_back({Vec3d(0.1, h, -0.2), intensity});
    RadiosityOptions options;
    options.patches = 128;
    Prepared p = Prepare(scene, options);
    ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
    const RadiosityRenderer& r = **p.renderer;
    ASSERT_EQ(r.report().sides, r.report().patches) << "only the lit front side has unknowns";
    for (const PatchMesh::Side& side : r.mesh().sides()) {
        const PatchMesh::Patch& patch = r.mesh().patches()[size_t(side.patch)];
        const Vec3d& a = r.mesh().vertices()[patch.vertices[0]];
        const Vec3d& b = r.mesh().vertices()[patch.vertices[1]];
        const Vec3d& c = r.mesh().vertices()[patch.vertices[2]];
        constexpr int kN = 64;  // midpoints of a kN x kN barycentric grid
        double sum = 0;
        int count = 0;
        for (int i = 0; i < kN; ++i) {
            for (int j = 0; i + j < kN; ++j) {
                for (int up = 0; up < (i + j + 1 < kN ? 2 : 1); ++up) {
                    const double u = (i + (up ? 2.0 : 1.0) / 3) / kN;
                    const double v = (j + (up ? 2.0 : 1.0) / 3) / kN;
                    const Vec3d x = a + (b - a) * u + (c - a) * v;
                    const Vec3d d = scene.point_lights[0].position - x;
                    sum += d.y / std::pow(LengthSquared(d), 1.5);
                    ++count;
                }
            }
        }
        const Rgb expected = floor.reflectance * intensity * float(sum / count);
        const Rgb& got = r.radiosity()[size_t(&side - r.mesh().sides().data())];
        for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(got[ch], expected[ch], 5e-4 * expected[ch]);
    }
}

TEST(Radiosity, SavedSolutionRendersAnotherCameraWithoutSolving) {
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.6f, 1.0f, 12);
    scene.content_hash = "furnace-v1";
    scene.materials.push_back(scene.materials[0]);
    scene.materials[1].emission = Rgb(0);
    scene.materials[1].reflectance = Rgb(0.2f, 0.5f, 0.8f);
    scene.meshes[2].material = 1;  // a coloured wall, so the solution is not uniform
    const std::string path = TempPath("radiosity_solution");
    RadiosityOptions save;
    save.patches = 200;
    save.save_solution = path;
    Prepared solved = Prepare(scene, save);
    ASSERT_TRUE(solved.renderer.ok()) << solved.renderer.status();
    EXPECT_FALSE((*solved.renderer)->report().loaded);

    RadiosityOptions load;
    load.patches = 7;  // ignored: the solution's meshing wins
    load.load_solution = path;
    Prepared loaded = Prepare(scene, load);
    ASSERT_TRUE(loaded.renderer.ok()) << loaded.renderer.status();
    const RadiosityRenderer &a = **solved.renderer, &b = **loaded.renderer;
    EXPECT_TRUE(b.report().loaded);
    EXPECT_EQ(b.report().form_factor_seconds, 0);
    EXPECT_EQ(b.report().iterations, a.report().iterations);
    ASSERT_EQ(a.radiosity().size(), b.radiosity().size());
    EXPECT_TRUE(std::equal(a.radiosity().begin(), a.radiosity().end(), b.radiosity().begin()));

    CameraSpec other = scene.camera;
    other.look_at = Vec3d(-1, -0.5, 0.3);
    const Camera camera(other, solved.embree->origin());
    RenderSettings settings;
    settings.spp = 1;
    EXPECT_EQ(*RenderImage(camera, a, settings).value().image.FindChannel("R"),
              *RenderImage(camera, b, settings).value().image.FindChannel("R"));

    // Another scene content: refused, naming both hashes.
    Scene changed = scene;
    changed.content_hash = "furnace-v2";
    Prepared wrong_scene = Prepare(changed, load);
    ASSERT_EQ(wrong_scene.renderer.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(wrong_scene.renderer.status().message().find("furnace-v1"), std::string::npos);

    // Same hash but other geometry (a scene built in code): the patch count gives it away.
    Scene bigger = testing::MakeFurnace(2.0, Vec3d(), 0.6f, 1.0f, 12);
    bigger.content_hash = scene.content_hash;
    Prepared wrong_mesh = Prepare(bigger, load);
    ASSERT_EQ(wrong_mesh.renderer.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(wrong_mesh.renderer.status().message().find("patches"), std::string::npos);

    std::ofstream(path, std::ios::binary | std::ios::trunc) << "LFRADSOL garbage";
    Prepared corrupt = Prepare(scene, load);
    EXPECT_EQ(corrupt.renderer.status().code(), absl::StatusCode::kInvalidArgument);
    fs::remove(path);
}

// A closed box with k x k subdivided faces: each face shares its (k+1)^2 grid vertices between
// its 2 k^2 patches, and only the inward sides exist.
TEST(Radiosity, PlyExportWritesTheSharedVertices) {
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    const std::string path = TempPath("radiosity.ply");
    RadiosityOptions options;
    options.patch_size = 2 * std::sqrt(2.0) / 2.99;  // just over a face diagonal / 3: k = 3
    options.export_ply = path;
    Prepared p = Prepare(scene, options);
    ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
    std::ifstream in(path);
    std::string line;
    int64_t vertices = -1, faces = -1, body_lines = 0;
    bool in_body = false;
    while (std::getline(in, line)) {
        if (in_body) {
            ++body_lines;
        } else if (line.rfind("element vertex ", 0) == 0) {
            vertices = std::stoll(line.substr(15));
        } else if (line.rfind("element face ", 0) == 0) {
            faces = std::stoll(line.substr(13));
        } else if (line == "end_header") {
            in_body = true;
        }
    }
    EXPECT_EQ(vertices, 6 * 4 * 4);
    EXPECT_EQ(faces, 6 * 2 * 3 * 3);
    EXPECT_EQ(body_lines, vertices + faces);
    fs::remove(path);
}

TEST(Radiosity, RefusesWhatItCannotRepresent) {
    Scene spheres = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    spheres.spheres.push_back({"ball", 0, Vec3d(), 0.2});
    EXPECT_EQ(Prepare(spheres, {}).renderer.status().code(), absl::StatusCode::kInvalidArgument);

    Scene glossy = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    glossy.materials[0].type = Material::Type::kGlossy;
    EXPECT_EQ(Prepare(glossy, {}).renderer.status().code(), absl::StatusCode::kInvalidArgument);

    Scene white = testing::MakeFurnace(1.0, Vec3d(), 1.0f, 1.0f, 8);
    const auto refused = Prepare(white, {}).renderer.status();
    EXPECT_EQ(refused.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(refused.message().find("'furnace'"), std::string::npos) << refused;
}

TEST(Radiosity, SameSolutionForAnyThreadCount) {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    std::vector<std::vector<Rgb>> solutions;
    for (int threads : {1, 2}) {
        RadiosityOptions options;
        options.patches = 600;
        options.threads = threads;
        Prepared p = Prepare(*scene, options);
        ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
        solutions.emplace_back((*p.renderer)->radiosity().begin(),
                               (*p.renderer)->radiosity().end());
    }
    EXPECT_EQ(solutions[0], solutions[1]);
}

TEST(Radiosity, ParsesDisplayNames) {
    EXPECT_EQ(*ParseRadiosityShading("flat"), RadiosityShading::kFlat);
    EXPECT_EQ(*ParseRadiosityShading("smooth"), RadiosityShading::kSmooth);
    EXPECT_EQ(ParseRadiosityShading("gouraud").status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
