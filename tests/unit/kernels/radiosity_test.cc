// The radiosity facade: rendering a furnace through the tile renderer, point lights against
// their closed form, saving and loading solutions (and refusing mismatched ones), the PLY
// export, refusals of scenes radiosity cannot represent, and thread-count independence.
#include "lf/kernels/radiosity.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/radiosity_refinement.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/local_executor.h"
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
    const auto ha = a.display().irradiance(), hb = b.display().irradiance();
    ASSERT_EQ(ha.size(), hb.size());
    EXPECT_TRUE(std::equal(ha.begin(), ha.end(), hb.begin()));

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

    // Version 2 held the radiosity only, whose irradiance is unknown where ρ is 0: solve again.
    {
        std::ofstream old(path, std::ios::binary | std::ios::trunc);
        const uint32_t version = 2;
        old << "LFRADSOL";
        old.write(reinterpret_cast<const char*>(&version), sizeof version);
    }
    Prepared old = Prepare(scene, load);
    EXPECT_EQ(old.renderer.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(old.renderer.status().message().find("version 2"), std::string::npos)
        << old.renderer.status();
    fs::remove(path);
}

// A closed box with k x k subdivided faces: each face shares its (k+1)^2 grid vertices between
// its 2 k^2 patches, and only the inward sides exist. Every vertex carries the furnace's
// illuminance, pi Le / (1 - rho) W m^-2 at 683 lm/W.
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
    bool in_body = false, has_illuminance = false;
    const double lux = 683 * std::numbers::pi * 1.0 / (1 - 0.5);
    while (std::getline(in, line)) {
        if (in_body) {
            ++body_lines;
            if (body_lines <= vertices) {
                std::istringstream fields(line);
                double x, y, z, illuminance = 0;
                int r, g, b;
                fields >> x >> y >> z >> r >> g >> b >> illuminance;
                EXPECT_NEAR(illuminance, lux, 0.01 * lux) << line;
            }
        } else if (line == "property float illuminance") {
            has_illuminance = true;
        } else if (line.rfind("element vertex ", 0) == 0) {
            vertices = std::stoll(line.substr(15));
        } else if (line.rfind("element face ", 0) == 0) {
            faces = std::stoll(line.substr(13));
        } else if (line == "end_header") {
            in_body = true;
        }
    }
    EXPECT_TRUE(has_illuminance);
    EXPECT_EQ(vertices, 6 * 4 * 4);
    EXPECT_EQ(faces, 6 * 2 * 3 * 3);
    EXPECT_EQ(body_lines, vertices + faces);
    fs::remove(path);
}

// A square emitter of radiance Le between two equal receivers at equal distances above and
// below it, each facing it. The emitter's front faces up: one-sided it leaves the lower receiver
// dark; two-sided its back has radiosity pi Le too and the lower receiver gets what the upper
// one does (mirror images: the same form factors up to their quadrature, 5e-4).
TEST(Radiosity, TwoSidedEmitterLightsBothSides) {
    const float le = 2.0f;
    for (const bool two_sided : {false, true}) {
        Scene scene;
        Material emitter;
        emitter.reflectance = Rgb(0.0f);
        emitter.emission = Rgb(le);
        emitter.two_sided_emission = two_sided;
        Material receiver;
        receiver.reflectance = Rgb(0.5f);
        scene.materials = {emitter, receiver};
        const auto square = [&](double y, bool up, int material) {
            TriangleMesh m;
            m.material = material;
            m.is_quad = true;
            m.positions = {{-0.5, y, -0.5}, {-0.5, y, 0.5}, {0.5, y, 0.5}, {0.5, y, -0.5}};
            m.triangles = up ? std::vector<std::array<uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}}
                             : std::vector<std::array<uint32_t, 3>>{{0, 2, 1}, {0, 3, 2}};
            return m;
        };
        scene.meshes = {square(0, true, 0), square(0.7, false, 1), square(-0.7, true, 1)};
        RadiosityOptions options;
        options.patches = 96;
        Prepared p = Prepare(scene, options);
        ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
        const RadiosityRenderer& r = **p.renderer;
        double power[3] = {};  // per mesh, front sides only for the receivers
        // The emitter's back faces the lower receiver, so it has an unknown either way (its
        // illuminance), and radiosity only when two-sided.
        int emitter_back = 0;
        for (size_t s = 0; s < r.mesh().sides().size(); ++s) {
            const PatchMesh::Side& side = r.mesh().sides()[s];
            const PatchMesh::Patch& patch = r.mesh().patches()[size_t(side.patch)];
            if (patch.mesh == 0 && side.back) {
                ++emitter_back;
                EXPECT_NEAR(r.radiosity()[s].r, two_sided ? kPi * le : 0, 1e-5 * kPi * le);
            }
            if (patch.mesh > 0 && side.back) continue;
            power[patch.mesh] += patch.area * r.radiosity()[s].r;
        }
        EXPECT_GT(emitter_back, 0);
        EXPECT_GT(power[1], 0);
        if (two_sided) {
            EXPECT_NEAR(power[2], power[1], 1e-3 * power[1]);
        } else {
            EXPECT_EQ(power[2], 0);
        }
    }
}

TEST(Radiosity, RefusesWhatItCannotRepresent) {
    Scene spheres = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    spheres.spheres.push_back({"ball", 0, Vec3d(), 0.2});
    EXPECT_EQ(Prepare(spheres, {}).renderer.status().code(), absl::StatusCode::kInvalidArgument);

    Scene masked = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    masked.materials[0].alpha_mode = Material::AlphaMode::kMask;
    EXPECT_EQ(Prepare(masked, {}).renderer.status().code(), absl::StatusCode::kInvalidArgument);

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

// Mean area and count of the patches of mesh `name` whose centroid is within `radius` of
// `centre` (distance in the mesh's plane, the centre given on it).
struct Region {
    double mean_area = 0;
    int count = 0;
};

Region PatchesNear(const Scene& scene, const PatchMesh& mesh, const std::string& name,
                   const Vec3d& centre, double radius) {
    Region r;
    for (int64_t p = 0; p < int64_t(mesh.patches().size()); ++p) {
        const PatchMesh::Patch& patch = mesh.patches()[size_t(p)];
        if (scene.meshes[size_t(patch.mesh)].name != name) continue;
        if (Length(mesh.Centroid(p) - centre) >= radius) continue;
        r.mean_area += patch.area;
        ++r.count;
    }
    r.mean_area /= std::max(r.count, 1);
    return r;
}

Scene CornellBox() {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    EXPECT_TRUE(scene.ok()) << scene.status();
    return *scene;
}

// From 250 patches to a target of 0.1: the refinement stops with every indicator at or below
// the target (the budget, 16 x 242 patches, is not reached), and splits where the radiosity
// varies, not everywhere.
TEST(Radiosity, RefinementIsLocalAndMeetsTheTarget) {
    const Scene scene = CornellBox();
    RadiosityOptions options;
    options.patches = 250;
    options.target_error = 0.1;
    Prepared p = Prepare(scene, options);
    ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
    const RadiosityRenderer& r = **p.renderer;
    const RadiosityReport& report = r.report();
    ASSERT_GE(report.refinement.size(), 2u);
    EXPECT_EQ(report.refinement.front().patches, 242);
    EXPECT_EQ(report.refinement.back().patches, report.patches);
    EXPECT_EQ(report.refinement.back().split, 0);
    for (size_t pass = 1; pass < report.refinement.size(); ++pass) {
        const RadiosityRefinementPass &before = report.refinement[pass - 1],
                                      &after = report.refinement[pass];
        EXPECT_EQ(after.patches, before.patches + 3 * before.split);
    }
    EXPECT_FALSE(report.budget_reached);
    EXPECT_EQ(report.finest_above_target, 0);
    EXPECT_LE(report.estimated_error, options.target_error);
    EXPECT_LT(report.mean_estimated_error, report.refinement.front().mean_error);
    EXPECT_LE(report.residual, options.target_error / 10);  // the solver's tolerance follows

    // Recomputed from the returned solution, the indicator agrees with the report.
    const DiscretisationError error = EstimateDiscretisationError(r.mesh(), r.radiosity());
    EXPECT_EQ(error.max, report.estimated_error);

    // Measured: 17 patches of 1.14e-3 m^2 on the ceiling within 10 cm of the light's centre,
    // 27 of 1.0e-3 on the floor under it, 12 of 2.37e-3 in the middle of the back wall (one
    // split of its 9.5e-3 coarse patches).
    const Region ceiling =
        PatchesNear(scene, r.mesh(), "ceiling", Vec3d(0.278, 0.5488, 0.2795), 0.1);
    const Region floor = PatchesNear(scene, r.mesh(), "floor", Vec3d(0.278, 0, 0.2795), 0.1);
    const Region back = PatchesNear(scene, r.mesh(), "back", Vec3d(0.278, 0.2744, 0.5592), 0.1);
    ASSERT_GT(back.count, 0);
    EXPECT_LT(ceiling.mean_area, 0.6 * back.mean_area);
    EXPECT_LT(floor.mean_area, 0.6 * back.mean_area);
    // ... and every large surface keeps coarse patches where nothing varies.
    for (const std::string name : {"back", "ceiling", "floor", "left_red", "right_green"}) {
        int coarse = 0, fine = 0;
        for (const PatchMesh::Patch& patch : r.mesh().patches()) {
            if (scene.meshes[size_t(patch.mesh)].name != name) continue;
            (patch.level == 0 ? coarse : fine) += 1;
        }
        EXPECT_GT(coarse, 0) << name;
        EXPECT_GT(fine, 0) << name;
    }
}

// Each pass reuses the previous pass's form factors for the pairs of patches it did not split,
// and the result is the bits of computing them all: the final mesh built directly from its split
// cells, its form factors computed afresh and solved to the same tolerance (the default 1e-4,
// below target / 10), gives the same radiosity bit for bit.
TEST(Radiosity, RefinementReusesFormFactorsWithTheSameBits) {
    const Scene scene = CornellBox();
    RadiosityOptions options;
    options.patches = 250;
    options.target_error = 0.1;
    ASSERT_LT(options.tolerance, options.target_error / 10);
    Prepared p = Prepare(scene, options);
    ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
    const RadiosityRenderer& r = **p.renderer;

    absl::StatusOr<PatchMesh> mesh =
        PatchMesh::Build(scene, {r.mesh().patch_size(), 0, r.mesh().split()});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    const FormFactors fresh = ComputeFormFactors(*p.embree, *mesh);
    const absl::StatusOr<SolveResult> solved =
        SolveRadiosity(MakeRadiositySystem(*p.embree, *mesh, fresh),
                       {options.solver, options.tolerance, options.max_iterations});
    ASSERT_TRUE(solved.ok()) << solved.status();
    ASSERT_EQ(solved->radiosity.size(), r.radiosity().size());
    for (size_t s = 0; s < solved->radiosity.size(); ++s) {
        const Rgb &a = solved->radiosity[s], &b = r.radiosity()[s];
        ASSERT_EQ(std::bit_cast<uint32_t>(a.r), std::bit_cast<uint32_t>(b.r)) << "side " << s;
        ASSERT_EQ(std::bit_cast<uint32_t>(a.g), std::bit_cast<uint32_t>(b.g)) << "side " << s;
        ASSERT_EQ(std::bit_cast<uint32_t>(a.b), std::bit_cast<uint32_t>(b.b)) << "side " << s;
    }

    // Every pass after the first evaluates only the pairs with a new patch. The last one follows
    // the split of a single cell, 4 new of 527 patches, ~1 % of the pairs (measured: 1.8 k of
    // 152 k pairs evaluated, 2.1 k of 244 k rays cast).
    const std::vector<RadiosityRefinementPass>& passes = r.report().refinement;
    ASSERT_GE(passes.size(), 3u);
    EXPECT_EQ(passes.front().reused_pairs, 0);
    for (size_t pass = 1; pass < passes.size(); ++pass) {
        EXPECT_GT(passes[pass].reused_pairs, 0) << pass;
    }
    const RadiosityRefinementPass& last = passes.back();
    EXPECT_EQ(last.pairs + last.reused_pairs, fresh.work().pairs);
    EXPECT_LT(last.pairs, fresh.work().pairs / 20);
    EXPECT_LT(last.visibility_rays, fresh.work().rays / 20);
    int64_t rays = 0;
    for (const RadiosityRefinementPass& pass : passes) rays += pass.visibility_rays;
    EXPECT_EQ(rays, r.report().visibility_rays);
}

// A budget below what the target needs: refinement stops at it, splitting the worst patches
// first, and says so.
TEST(Radiosity, RefinementStopsAtThePatchBudget) {
    const Scene scene = CornellBox();
    RadiosityOptions options;
    options.patches = 250;
    options.target_error = 0.01;
    options.max_patches = 400;
    Prepared p = Prepare(scene, options);
    ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
    const RadiosityReport& report = (*p.renderer)->report();
    EXPECT_TRUE(report.budget_reached);
    EXPECT_LE(report.patches, options.max_patches);
    EXPECT_GT(report.patches, options.max_patches - 3);  // whatever room is left is used
    EXPECT_GT(report.estimated_error, options.target_error);

    // The choice itself: worst first, three patches per split.
    const PatchMesh& mesh = (*p.renderer)->mesh();
    const DiscretisationError error = EstimateDiscretisationError(mesh, (*p.renderer)->radiosity());
    const int64_t room = 30;
    const RefinementStep step =
        ChooseRefinement(mesh, error, 0.01, int64_t(mesh.patches().size()) + room);
    ASSERT_EQ(int64_t(step.split.size()), room / 3);
    EXPECT_TRUE(step.budget_reached);
    double weakest_chosen = 1e300;
    std::set<PatchCell> chosen(step.split.begin(), step.split.end());
    for (int64_t q = 0; q < int64_t(mesh.patches().size()); ++q) {
        if (chosen.contains(mesh.Cell(q)))
            weakest_chosen = std::min(weakest_chosen, error.indicator[size_t(q)]);
    }
    for (int64_t q = 0; q < int64_t(mesh.patches().size()); ++q) {
        if (!chosen.contains(mesh.Cell(q))) {
            EXPECT_LE(error.indicator[size_t(q)], weakest_chosen);
        }
    }
}

// The refined mesh and its solution are the same bits for any thread count, and save, load
// and export like an unrefined one.
TEST(Radiosity, RefinedSolutionIsDeterministicAndSavesAndLoads) {
    const Scene scene = [] {
        Scene s = CornellBox();
        s.camera.width = s.camera.height = 32;
        return s;
    }();
    const std::string solution = TempPath("refined_solution"), ply = TempPath("refined.ply");
    std::vector<Prepared> runs;
    for (int threads : {1, 2}) {
        RadiosityOptions options;
        options.patches = 150;
        options.target_error = 0.15;
        options.threads = threads;
        if (threads == 2) {
            options.save_solution = solution;
            options.export_ply = ply;
        }
        runs.push_back(Prepare(scene, options));
        ASSERT_TRUE(runs.back().renderer.ok()) << runs.back().renderer.status();
    }
    const RadiosityRenderer &one = **runs[0].renderer, &two = **runs[1].renderer;
    EXPECT_GT(one.report().refinement.size(), 1u);
    EXPECT_EQ(one.mesh().split(), two.mesh().split());
    ASSERT_EQ(one.radiosity().size(), two.radiosity().size());
    EXPECT_TRUE(
        std::equal(one.radiosity().begin(), one.radiosity().end(), two.radiosity().begin()));

    RadiosityOptions load;
    load.load_solution = solution;
    Prepared loaded = Prepare(scene, load);
    ASSERT_TRUE(loaded.renderer.ok()) << loaded.renderer.status();
    const RadiosityRenderer& l = **loaded.renderer;
    EXPECT_TRUE(l.report().loaded);
    EXPECT_EQ(l.report().patches, two.report().patches);
    EXPECT_EQ(l.mesh().split(), two.mesh().split());
    EXPECT_TRUE(std::equal(l.radiosity().begin(), l.radiosity().end(), two.radiosity().begin()));
    const Camera camera(scene.camera, loaded.embree->origin());
    RenderSettings settings;
    settings.spp = 1;
    const Image image = RenderImage(camera, l, settings).value().image;
    EXPECT_EQ(*image.FindChannel("G"),
              *RenderImage(camera, two, settings).value().image.FindChannel("G"));
    for (float v : *image.FindChannel("G")) ASSERT_TRUE(std::isfinite(v));

    // PLY: one face per side.
    std::ifstream in(ply);
    std::string line;
    int64_t faces = -1;
    while (std::getline(in, line) && line != "end_header") {
        if (line.rfind("element face ", 0) == 0) faces = std::stoll(line.substr(13));
    }
    EXPECT_EQ(faces, two.report().sides);
    fs::remove(solution);
    fs::remove(ply);
}

// The farm's sweeps solve one fixed mesh: a target error is refused there, not ignored.
TEST(Radiosity, SweepsRefuseATargetError) {
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 8);
    auto embree = EmbreeScene::Build(scene);
    ASSERT_TRUE(embree.ok()) << embree.status();
    RadiosityOptions options;
    options.patches = 50;
    options.target_error = 0.1;
    EXPECT_EQ(RadiositySweepChunks::Make(**embree, options, 1).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(RadiosityRendererFor(**embree, options, {}).status().code(),
              absl::StatusCode::kInvalidArgument);
    // Without a target the report has no refinement passes.
    options.target_error = 0;
    Prepared p = Prepare(scene, options);
    ASSERT_TRUE(p.renderer.ok()) << p.renderer.status();
    EXPECT_TRUE((*p.renderer)->report().refinement.empty());
}

TEST(Radiosity, ParsesDisplayNames) {
    EXPECT_EQ(*ParseRadiosityShading("flat"), RadiosityShading::kFlat);
    EXPECT_EQ(*ParseRadiosityShading("smooth"), RadiosityShading::kSmooth);
    EXPECT_EQ(ParseRadiosityShading("gouraud").status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
