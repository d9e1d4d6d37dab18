// Hierarchical radiosity with clustering (radiosity_hierarchy.h): agreement with the flat solve
// on the Cornell box as the link error falls, the furnace's closed form, two unit plates against
// their closed-form form factors, an enclosure's energy balance, links per side bounded as the
// mesh grows 16-fold, and the farm's sweep chunks giving PrepareRadiosity's bits.
#include "lf/kernels/radiosity_hierarchy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>

#include "lf/core/scene_loader.h"
#include "lf/job/radiosity_solve.h"
#include "lf/job/render_metadata.h"
#include "lf/kernels/radiosity.h"
#include "test_scenes.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

struct Solved {
    Scene scene;
    std::unique_ptr<EmbreeScene> embree;
    std::unique_ptr<RadiosityRenderer> renderer;
};

// The scene must outlive the renderer (EmbreeScene keeps a reference).
std::unique_ptr<Solved> Solve(Scene scene, const RadiosityOptions& options) {
    auto s = std::make_unique<Solved>();
    s->scene = std::move(scene);
    auto es = EmbreeScene::Build(s->scene);
    EXPECT_TRUE(es.ok()) << es.status();
    s->embree = std::move(*es);
    auto r = PrepareRadiosity(*s->embree, options);
    EXPECT_TRUE(r.ok()) << r.status();
    if (r.ok()) s->renderer = std::move(*r);
    return s;
}

Scene CornellBox() {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    EXPECT_TRUE(scene.ok()) << scene.status();
    return *scene;
}

RadiosityOptions Hierarchical(double link_error) {
    RadiosityOptions options;
    options.hierarchical = true;
    options.link_error = link_error;
    options.tolerance = 1e-5;
    return options;
}

// Per scene mesh and side (front / back): the area-weighted mean radiosity, channels summed.
std::map<std::pair<int32_t, bool>, double> SurfaceMeans(const RadiosityRenderer& r) {
    std::map<std::pair<int32_t, bool>, std::pair<double, double>> sums;
    for (size_t s = 0; s < r.radiosity().size(); ++s) {
        const PatchMesh::Side& side = r.mesh().sides()[s];
        const PatchMesh::Patch& patch = r.mesh().patches()[size_t(side.patch)];
        const Rgb& b = r.radiosity()[s];
        auto& [power, area] = sums[{patch.mesh, side.back}];
        power += patch.area * (double(b.r) + b.g + b.b);
        area += patch.area;
    }
    std::map<std::pair<int32_t, bool>, double> means;
    for (const auto& [key, sum] : sums) means[key] = sum.first / sum.second;
    return means;
}

// The largest relative difference of a lit surface's mean (those above 1 % of the brightest).
double LargestSurfaceDifference(const RadiosityRenderer& a, const RadiosityRenderer& reference) {
    const auto ma = SurfaceMeans(a), mr = SurfaceMeans(reference);
    double brightest = 0, worst = 0;
    for (const auto& [key, m] : mr) brightest = std::max(brightest, m);
    for (const auto& [key, m] : mr) {
        if (m > 0.01 * brightest) worst = std::max(worst, std::abs(ma.at(key) / m - 1));
    }
    return worst;
}

// The Cornell box at ~1000 patches: per surface within 1 % of flat Jacobi from the default link
// error (1e-3: 0.4 %) down, and the difference falls as the link error does (at 1e-5 nearly all
// links are between sides, the flat method's form factors).
TEST(RadiosityHierarchy, ConvergesToTheFlatSolution) {
    RadiosityOptions flat;
    flat.patches = 1000;
    flat.solver = RadiositySolver::kJacobi;
    flat.tolerance = 1e-5;
    const auto reference = Solve(CornellBox(), flat);
    ASSERT_TRUE(reference->renderer);
    double previous = 1e300;
    for (double link_error : {1e-2, 1e-3, 1e-4, 1e-5}) {
        RadiosityOptions options = Hierarchical(link_error);
        options.patches = flat.patches;
        const auto h = Solve(CornellBox(), options);
        ASSERT_TRUE(h->renderer);
        const RadiosityReport& report = h->renderer->report();
        EXPECT_EQ(report.sides, reference->renderer->report().sides);
        EXPECT_EQ(report.form_factor_bytes, 0u);  // no flat form factors built
        EXPECT_GT(report.side_links, 0);
        const double difference = LargestSurfaceDifference(*h->renderer, *reference->renderer);
        std::printf(
            "link error %g: %lld + %lld links (%.1f per side), %.2f s, surface difference "
            "%.4f\n",
            link_error, (long long)report.cluster_links, (long long)report.side_links,
            report.links_per_side, report.form_factor_seconds + report.solve_seconds, difference);
        EXPECT_LT(difference, previous) << link_error;
        if (link_error <= 1e-3) {
            EXPECT_LT(difference, 0.01) << link_error;
        }
        previous = difference;
    }
    EXPECT_LT(previous, 1e-3);
}

// A closed box of uniform emission and reflectance: B = E / (1 - ρ) on every side.
TEST(RadiosityHierarchy, FurnaceGivesEmissionOverOneMinusRho) {
    const float rho = 0.7f, le = 0.5f;
    RadiosityOptions options = Hierarchical(1e-4);
    options.patches = 600;
    const auto h = Solve(testing::MakeFurnace(1.0, Vec3d(0.3, -0.2, 0.1), rho, le, 8), options);
    ASSERT_TRUE(h->renderer);
    const double expected = kPi * le / (1 - rho);
    double worst = 0, power = 0, area = 0;
    const RadiosityRenderer& r = *h->renderer;
    for (size_t s = 0; s < r.radiosity().size(); ++s) {
        const double a = r.mesh().patches()[size_t(r.mesh().sides()[s].patch)].area;
        worst = std::max(worst, std::abs(r.radiosity()[s].r / expected - 1));
        power += a * r.radiosity()[s].r;
        area += a;
    }
    EXPECT_NEAR(power / area, expected, 0.005 * expected);
    EXPECT_LT(worst, 0.02);
}

// Unit plate 0 emits (black), unit plate 1 (ρ = 0.5) receives: its mean irradiance is
// F_10 π L_e, the closed-form form factor of the two squares.
double ReceivedFormFactor(bool perpendicular) {
    Scene scene;
    Material emitter, receiver;
    emitter.reflectance = Rgb(0);
    emitter.emission = Rgb(1);
    receiver.reflectance = Rgb(0.5f);
    scene.materials = {emitter, receiver};
    testing::AddQuad(scene, 0, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});  // z = 0, normal +z
    if (perpendicular) {
        testing::AddQuad(scene, 1, {0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1});  // normal +x
    } else {
        testing::AddQuad(scene, 1, {0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1});  // normal -z
    }
    RadiosityOptions options = Hierarchical(1e-4);
    options.patches = 400;
    const auto h = Solve(std::move(scene), options);
    if (!h->renderer) return -1;
    const RadiosityRenderer& r = *h->renderer;
    double received = 0;
    for (size_t s = 0; s < r.radiosity().size(); ++s) {
        const PatchMesh::Side& side = r.mesh().sides()[s];
        const PatchMesh::Patch& patch = r.mesh().patches()[size_t(side.patch)];
        if (patch.mesh == 1 && !side.back) received += patch.area * r.radiosity()[s].r / 0.5;
    }
    return received / kPi;  // the receiver's area is 1
}

TEST(RadiosityHierarchy, UnitPlatesMatchTheirClosedForms) {
    // Siegel & Howell: parallel unit squares at unit distance, perpendicular ones sharing an
    // edge (form_factors_test.cc derives both).
    EXPECT_NEAR(ReceivedFormFactor(false), 0.199825, 0.01 * 0.199825);
    EXPECT_NEAR(ReceivedFormFactor(true), 0.200044, 0.01 * 0.200044);
}

// In a closed box with one emitting wall and walls of different reflectances, all emitted power
// is absorbed: Σ A E = Σ A (1 - ρ) H, H = (B - E) / ρ the irradiance (every wall here has ρ > 0,
// so this is the carried H too). Links between clusters
// approximate the transport (1 % too much at a link error of 1e-4, 0.06 % at 1e-5); between
// sides it is exact.
double AbsorbedOverEmitted(double link_error) {
    Scene scene;
    testing::AddInwardBox(scene, Vec3d(0, 0, 0), 1.0, 0);
    for (int wall = 0; wall < 6; ++wall) {
        Material m;
        m.reflectance = Rgb(0.2f + 0.12f * float(wall));
        if (wall == 1) m.emission = Rgb(2);
        scene.materials.push_back(m);
        scene.meshes[size_t(wall)].material = wall;
    }
    RadiosityOptions options = Hierarchical(link_error);
    options.patches = 800;
    const auto h = Solve(std::move(scene), options);
    if (!h->renderer) return 0;
    const RadiosityRenderer& r = *h->renderer;
    double emitted = 0, absorbed = 0;
    for (size_t s = 0; s < r.radiosity().size(); ++s) {
        const PatchMesh::Patch& patch = r.mesh().patches()[size_t(r.mesh().sides()[s].patch)];
        const Material& m =
            h->scene.materials[size_t(h->scene.meshes[size_t(patch.mesh)].material)];
        const double e = kPi * m.emission.r, rho = m.reflectance.r;
        emitted += patch.area * e;
        absorbed += patch.area * (1 - rho) * (r.radiosity()[s].r - e) / rho;
    }
    return absorbed / emitted;
}

TEST(RadiosityHierarchy, EnclosureAbsorbsWhatItEmits) {
    EXPECT_NEAR(AbsorbedOverEmitted(1e-4), 1, 0.02);
    EXPECT_NEAR(AbsorbedOverEmitted(1e-5), 1, 0.002);
}

// Links per side stay bounded as the Cornell box goes from ~1000 to ~16000 patches.
TEST(RadiosityHierarchy, LinksPerSideStayBounded) {
    const Scene scene = CornellBox();
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    double per_side[2] = {0, 0};
    const int64_t patches[2] = {1000, 16000};
    for (int k = 0; k < 2; ++k) {
        auto mesh = PatchMesh::Build(scene, {0, patches[k]});
        ASSERT_TRUE(mesh.ok()) << mesh.status();
        const FormFactors none;
        auto h = RadiosityHierarchy::Build(**es, *mesh, MakeRadiositySystem(**es, *mesh, none),
                                           {.link_error = 1e-3});
        ASSERT_TRUE(h.ok()) << h.status();
        ASSERT_TRUE((*h)->Link(**es, *mesh, 0, 1).ok());
        per_side[k] = double((*h)->node_links() + (*h)->leaf_links()) / (*h)->sides();
        std::printf("%lld patches: %d sides, %lld + %lld links, %.1f per side, %.1f MiB\n",
                    (long long)patches[k], (*h)->sides(), (long long)(*h)->node_links(),
                    (long long)(*h)->leaf_links(), per_side[k], double((*h)->bytes()) / (1 << 20));
    }
    EXPECT_LT(per_side[1], 1.5 * per_side[0]);
}

// The solver's checks of E and rho hold on this path too: a side reflecting everything in an
// emitting scene has no finite solution, and a NaN would spread through every sweep.
TEST(RadiosityHierarchy, RefusesReflectanceOfOneAndNonFiniteValuesNamingTheSide) {
    const Scene scene = CornellBox();
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    auto mesh = PatchMesh::Build(scene, {0, 200});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    const FormFactors none;
    RadiositySystem bright = MakeRadiositySystem(**es, *mesh, none);
    bright.reflectance[3] = Rgb(1, 0.5f, 0.5f);
    auto h = RadiosityHierarchy::Build(**es, *mesh, bright, {});
    EXPECT_EQ(h.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(h.status().message().find("at side 3"), std::string::npos) << h.status();
    RadiositySystem nan = MakeRadiositySystem(**es, *mesh, none);
    nan.emission[5] = Rgb(NAN, 0, 0);
    h = RadiosityHierarchy::Build(**es, *mesh, nan, {});
    EXPECT_EQ(h.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(h.status().message().find("side 5"), std::string::npos) << h.status();
}

// The farm's way: chunks of the groups swept against each sweep's gathered irradiance, the sums
// added by RadiositySolve, give PrepareRadiosity's bits for any chunk count and any split of the
// chunks over workers (here two, one holding the even chunks, one the odd): the radiosity, and
// the irradiance with the point light's direct part, which RadiosityRendererFor computes again.
TEST(RadiosityHierarchy, SweepChunksGivePrepareRadiositysBits) {
    Scene scene = CornellBox();
    scene.point_lights.push_back({{0.278, 0.45, 0.28}, Rgb(0.4f, 0.3f, 0.2f)});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    RadiosityOptions options = Hierarchical(1e-3);
    options.patches = 2000;
    options.tolerance = 1e-4;
    auto local = PrepareRadiosity(**es, options);
    ASSERT_TRUE(local.ok()) << local.status();
    for (int chunks : {1, 2, 3, 7}) {
        std::vector<std::unique_ptr<RadiositySweepChunks>> workers;
        for (int w = 0; w < 2; ++w) {
            auto worker = RadiositySweepChunks::Make(**es, options, chunks);
            ASSERT_TRUE(worker.ok()) << worker.status();
            workers.push_back(std::move(*worker));
        }
        for (int c = 0; c < chunks; ++c) ASSERT_TRUE(workers[size_t(c % 2)]->Link(**es, c).ok());
        RadiositySolve solve(chunks, options.tolerance, options.max_iterations);
        std::vector<Rgb> h = workers[0]->start();  // the gathered irradiance
        for (;;) {
            for (int c = chunks - 1; c >= 0; --c) {
                auto result = workers[size_t(c % 2)]->Sweep(c, solve.sweep(), h);
                ASSERT_TRUE(result.ok()) << result.status();
                ASSERT_TRUE(solve.Add(*result).ok());
            }
            ASSERT_TRUE(solve.SweepComplete());
            auto outcome = solve.FinishSweep();
            ASSERT_TRUE(outcome.ok()) << outcome.status();
            h = std::move(outcome->radiosity);
            if (outcome->converged) break;
        }
        auto farm = RadiosityRendererFor(**es, options, h);
        ASSERT_TRUE(farm.ok()) << farm.status();
        for (const auto& [mine, theirs] :
             {std::pair((*farm)->radiosity(), (*local)->radiosity()),
              std::pair((*farm)->display().irradiance(), (*local)->display().irradiance())}) {
            ASSERT_EQ(mine.size(), theirs.size());
            EXPECT_TRUE(
                std::equal(mine.begin(), mine.end(), theirs.begin(),
                           [](Rgb x, Rgb y) { return x.r == y.r && x.g == y.g && x.b == y.b; }))
                << chunks << " chunks";
        }
    }
}

// With a target error every refinement pass solves hierarchically; the figures the EXR header
// and the farm carry count the links.
TEST(RadiosityHierarchy, RefinementPassesSolveHierarchically) {
    RadiosityOptions options = Hierarchical(1e-3);
    options.patches = 150;
    options.target_error = 0.2;
    const auto h = Solve(CornellBox(), options);
    ASSERT_TRUE(h->renderer);
    const RadiosityReport& report = h->renderer->report();
    ASSERT_GE(report.refinement.size(), 2u);
    EXPECT_GT(report.patches, report.refinement.front().patches);
    EXPECT_EQ(report.form_factor_bytes, 0u);
    EXPECT_EQ(report.refinement.back().pairs, 0);  // no flat form factors in any pass
    EXPECT_GT(report.refinement.back().visibility_rays, 0);
    const RadiosityFigures figures = RadiosityFiguresOf(report);
    EXPECT_EQ(figures.links, report.cluster_links + report.side_links);
    EXPECT_GT(figures.solver_bytes, figures.link_bytes);
    EXPECT_GT(figures.link_bytes, 0);
}

TEST(RadiosityHierarchy, CancelStopsTheBuild) {
    const Scene scene = CornellBox();
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    std::atomic<bool> cancel{true};
    RadiosityOptions options = Hierarchical(1e-3);
    options.cancel = &cancel;
    EXPECT_EQ(PrepareRadiosity(**es, options).status().code(), absl::StatusCode::kCancelled);
    EXPECT_EQ(RadiositySweepChunks::Make(**es, options, 2, &cancel).status().code(),
              absl::StatusCode::kCancelled);
    // A chunk whose linking is cancelled is not linked, and links whole when asked again.
    cancel = false;
    auto chunks = RadiositySweepChunks::Make(**es, options, 2, &cancel);
    ASSERT_TRUE(chunks.ok()) << chunks.status();
    cancel = true;
    EXPECT_EQ((*chunks)->Link(**es, 1, &cancel).code(), absl::StatusCode::kCancelled);
    EXPECT_FALSE((*chunks)->Linked(1));
    cancel = false;
    EXPECT_TRUE((*chunks)->Link(**es, 1, &cancel).ok());
    EXPECT_TRUE((*chunks)->Linked(1));
    EXPECT_FALSE((*chunks)->Linked(0));
    EXPECT_GT((*chunks)->LinkReport(1).side_links, 0);
}

}  // namespace
}  // namespace lf
