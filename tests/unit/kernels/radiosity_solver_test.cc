// The radiosity solvers: the furnace's closed form B = E / (1 - ρ) for every solver up to
// ρ = 0.99, agreement between solvers on the Cornell box, the iteration counts against ρ, the
// refusals (ρ >= 1 with emission, the iteration cap), and Jacobi / Gauss-Seidel as sequences of
// the pure group step.
#include "lf/kernels/radiosity_solver.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "lf/core/scene_loader.h"
#include "test_scenes.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// A scene with its mesh, form factors and the system B = E + ρ F B; E is π L_e on emitting
// front sides (no point lights in these scenes).
struct Problem {
    Scene scene;
    std::unique_ptr<EmbreeScene> embree;
    PatchMesh mesh;
    FormFactors ff;
    RadiositySystem system;
};

std::unique_ptr<Problem> MakeProblem(Scene scene, PatchMeshOptions options) {
    auto p = std::make_unique<Problem>();
    p->scene = std::move(scene);
    auto es = EmbreeScene::Build(p->scene);
    EXPECT_TRUE(es.ok()) << es.status();
    p->embree = std::move(*es);
    auto mesh = PatchMesh::Build(p->scene, options);
    EXPECT_TRUE(mesh.ok()) << mesh.status();
    p->mesh = std::move(*mesh);
    p->ff = ComputeFormFactors(*p->embree, p->mesh);
    p->system.form_factors = &p->ff;
    for (const PatchMesh::Side& side : p->mesh.sides()) {
        const PatchMesh::Patch& patch = p->mesh.patches()[size_t(side.patch)];
        const Material& m =
            p->scene.materials[size_t(p->scene.meshes[size_t(patch.mesh)].material)];
        p->system.emission.push_back(side.back ? Rgb(0) : m.emission * float(kPi));
        p->system.reflectance.push_back(m.reflectance);
        p->system.area.push_back(patch.area);
    }
    return p;
}

std::unique_ptr<Problem> Furnace(float rho, float le = 0.5f) {
    PatchMeshOptions options;
    options.patches = 200;
    return MakeProblem(testing::MakeFurnace(1.0, Vec3d(0.3, -0.2, 0.1), rho, le, 8), options);
}

// ||a - b|| / ||b|| in the solver's power norm.
double RelativeDifference(const RadiositySystem& system, std::span<const Rgb> a,
                          std::span<const Rgb> b) {
    double diff = 0, norm = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            diff += system.area[i] * std::abs(double(a[i][c]) - b[i][c]);
            norm += system.area[i] * std::abs(double(b[i][c]));
        }
    }
    return diff / norm;
}

double Norm(const RadiositySystem& system, std::span<const Rgb> b) {
    double norm = 0;
    for (size_t i = 0; i < b.size(); ++i) {
        norm += system.area[i] * (std::abs(b[i].r) + std::abs(b[i].g) + std::abs(b[i].b));
    }
    return norm;
}

double MaxRowSumDeviation(const FormFactors& ff) {
    double worst = 0;
    for (int32_t i = 0; i < ff.size(); ++i) worst = std::max(worst, std::abs(ff.RowSum(i) - 1));
    return worst;
}

// max_j Σ_i A_i F_ij / A_j: the norm of F in the power norm, so ||(I - ρF)^-1|| <= 1 / (1 - ρ c).
double PowerNormOfF(const RadiositySystem& system) {
    std::vector<double> column(system.area.size(), 0);
    for (const FormFactorBlock& block : system.form_factors->blocks()) {
        for (int32_t i = block.row_begin; i < block.row_end; ++i) {
            for (int32_t j = block.col_begin; j < block.col_end; ++j) {
                column[size_t(j)] += system.area[size_t(i)] * block.at(i, j);
            }
        }
    }
    double c = 0;
    for (size_t j = 0; j < column.size(); ++j) c = std::max(c, column[j] / system.area[j]);
    return c;
}

constexpr RadiositySolver kSolvers[] = {RadiositySolver::kJacobi, RadiositySolver::kGaussSeidel,
                                        RadiositySolver::kShooting};

// The uniform B* = E / (1 - ρ) solves the discrete system up to ρ B* (1 - s_i), s_i the row
// sums of F (within δ of 1 in a closed box, ClosedBoxRowsSumToOne); with the solver's residual
// r, ||B - B*|| <= (r ||B|| + ρ δ ||B*||) / (1 - ρ c), c the power norm of F.
TEST(RadiositySolver, FurnaceGivesEmissionOverOneMinusRho) {
    std::printf("%6s %-13s %10s %8s %10s\n", "rho", "solver", "iterations", "sweeps", "residual");
    for (float rho : {0.5f, 0.9f, 0.99f}) {
        auto p = Furnace(rho);
        const double delta = MaxRowSumDeviation(p->ff), c = PowerNormOfF(p->system);
        ASSERT_LT(rho * c, 1);
        const double expected = kPi * 0.5 / (1 - rho);
        std::vector<Rgb> exact(p->system.emission.size(), Rgb(float(expected)));
        for (RadiositySolver solver : kSolvers) {
            SolveOptions options;
            options.solver = solver;
            auto result = SolveRadiosity(p->system, options);
            ASSERT_TRUE(result.ok()) << result.status();
            EXPECT_LE(result->residual, options.tolerance);
            const double ratio = Norm(p->system, result->radiosity) / Norm(p->system, exact);
            const double bound = (result->residual * ratio + rho * delta) / (1 - rho * c);
            EXPECT_LE(RelativeDifference(p->system, result->radiosity, exact), bound)
                << RadiositySolverName(solver) << " rho " << rho;
            std::printf("%6.2f %-13s %10d %8.1f %10.2e\n", rho, RadiositySolverName(solver),
                        result->iterations, result->sweeps, result->residual);
        }
    }
}

// Jacobi from B = E in a furnace: B_k = E (1 - ρ^(k+1)) / (1 - ρ) and its relative residual is
// ρ^(k+1) (1 - ρ) / (1 - ρ^(k+1)), so the sweep count is known in advance: ~ ln ε / ln ρ.
TEST(RadiositySolver, JacobiSweepsMatchTheNeumannSeries) {
    for (float rho : {0.5f, 0.9f, 0.99f}) {
        auto p = Furnace(rho);
        SolveOptions options;
        options.solver = RadiositySolver::kJacobi;
        int k = 0;
        while (std::pow(double(rho), k + 1) * (1 - rho) / (1 - std::pow(double(rho), k + 1)) >
               options.tolerance) {
            ++k;
        }
        auto result = SolveRadiosity(p->system, options);
        ASSERT_TRUE(result.ok()) << result.status();
        // k sweeps to reach B_k and one to measure its residual; float rounding of ρ may move
        // the crossing by one.
        EXPECT_NEAR(result->iterations, k + 1, 1) << rho;
    }
}

std::unique_ptr<Problem> Cornell(int64_t patches) {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
    EXPECT_TRUE(scene.ok()) << scene.status();
    PatchMeshOptions options;
    options.patches = patches;
    return MakeProblem(std::move(*scene), options);
}

// Two solutions with residuals r_a and r_b differ by at most
// (r_a ||B_a|| + r_b ||B_b||) / (1 - ρ_max c), c the power norm of F (visibility sampling lets
// it exceed 1 slightly).
TEST(RadiositySolver, SolversAgreeOnTheCornellBox) {
    auto p = Cornell(500);
    double rho_max = 0;
    for (const Rgb& r : p->system.reflectance)
        rho_max = std::max(rho_max, double(r.MaxComponent()));
    const double c = PowerNormOfF(p->system);
    ASSERT_LT(rho_max * c, 1);
    std::vector<SolveResult> results;
    for (RadiositySolver solver : kSolvers) {
        SolveOptions options;
        options.solver = solver;
        auto result = SolveRadiosity(p->system, options);
        ASSERT_TRUE(result.ok()) << result.status();
        results.push_back(std::move(*result));
    }
    for (size_t a = 0; a < results.size(); ++a) {
        for (size_t b = a + 1; b < results.size(); ++b) {
            const double na = Norm(p->system, results[a].radiosity);
            const double nb = Norm(p->system, results[b].radiosity);
            const double bound =
                (results[a].residual * na / nb + results[b].residual) / (1 - rho_max * c);
            EXPECT_LE(RelativeDifference(p->system, results[a].radiosity, results[b].radiosity),
                      bound)
                << a << " vs " << b;
        }
    }
}

TEST(RadiositySolver, ReflectanceOfOneWithEmissionIsRefused) {
    auto p = Furnace(1.0f);
    for (RadiositySolver solver : kSolvers) {
        SolveOptions options;
        options.solver = solver;
        auto result = SolveRadiosity(p->system, options);
        ASSERT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(result.status().message().find("reflectance"), std::string::npos);
    }
    // Without emission the answer is simply dark.
    auto dark = Furnace(1.0f, 0.0f);
    auto result = SolveRadiosity(dark->system, {});
    ASSERT_TRUE(result.ok()) << result.status();
    for (const Rgb& b : result->radiosity) EXPECT_TRUE(b.IsBlack());
}

TEST(RadiositySolver, IterationCapIsAnError) {
    auto p = Furnace(0.99f);
    for (RadiositySolver solver : kSolvers) {
        SolveOptions options;
        options.solver = solver;
        options.max_iterations = 20;  // ρ = 0.99 needs ~900 sweeps
        auto result = SolveRadiosity(p->system, options);
        EXPECT_EQ(result.status().code(), absl::StatusCode::kResourceExhausted)
            << RadiositySolverName(solver);
    }
}

// The solvers are nothing but the pure step applied group by group: replaying them by hand
// gives the same bits, which is what lets a farm hand groups to workers.
TEST(RadiositySolver, SweepsAreSequencesOfThePureGroupStep) {
    auto p = Cornell(300);
    const auto& groups = p->ff.groups();
    ASSERT_GT(groups.size(), 3u);
    for (RadiositySolver solver : {RadiositySolver::kJacobi, RadiositySolver::kGaussSeidel}) {
        SolveOptions options;
        options.solver = solver;
        auto result = SolveRadiosity(p->system, options);
        ASSERT_TRUE(result.ok()) << result.status();
        // b = E + ρ h side by side, h the irradiance each side gathered last.
        std::vector<Rgb> b = p->system.emission, h(b.size()), next(b.size()), measured;
        const bool jacobi = solver == RadiositySolver::kJacobi;
        for (int k = 0; k < result->iterations; ++k) {
            measured = b;
            for (int32_t g = 0; g < int32_t(groups.size()); ++g) {
                const PatchGroup& group = groups[size_t(g)];
                std::span<Rgb> out(&next[size_t(group.begin)], size_t(group.size()));
                GatherGroup(*p->system.form_factors, g, b, out);
                if (jacobi) continue;
                for (int32_t i = group.begin; i < group.end; ++i) {
                    h[size_t(i)] = next[size_t(i)];
                    b[size_t(i)] =
                        RadiosityFromIrradiance(p->system.emission[size_t(i)],
                                                p->system.reflectance[size_t(i)], h[size_t(i)]);
                }
            }
            if (jacobi) {
                h.swap(next);
                b = RadiosityFromIrradiance(p->system, h);
            }
        }
        EXPECT_EQ(b, result->radiosity) << RadiositySolverName(solver);
        EXPECT_EQ(h, result->irradiance) << RadiositySolverName(solver);
        // Jacobi measured the radiosity its last sweep gathered from, Gauss-Seidel its result.
        EXPECT_NEAR(RelativeResidual(p->system, jacobi ? measured : b), result->residual, 1e-12);
    }
}

TEST(RadiositySolver, AmbientTermImprovesEarlyShootingPreviews) {
    auto p = Cornell(300);
    auto converged = SolveRadiosity(p->system, {RadiositySolver::kGaussSeidel, 1e-7, 10000});
    ASSERT_TRUE(converged.ok()) << converged.status();
    ShootingSolver shooter(p->system);
    for (int shot = 0; shot < 3; ++shot) {
        shooter.Shoot();
        const double plain =
            RelativeDifference(p->system, shooter.Radiosity(), converged->radiosity);
        const double ambient =
            RelativeDifference(p->system, shooter.Preview(), converged->radiosity);
        EXPECT_LT(ambient, plain) << "after " << shooter.shots() << " shots";
    }
}

TEST(RadiositySolver, ParsesNames) {
    for (RadiositySolver s : kSolvers) {
        EXPECT_EQ(*ParseRadiositySolver(RadiositySolverName(s)), s);
    }
    EXPECT_EQ(ParseRadiositySolver("gauss_seidel").status().code(),
              absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
