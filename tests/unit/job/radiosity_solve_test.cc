// The farm's sweep bookkeeping against a local Jacobi iteration of a small system written out
// by hand: b_{k+1} = E + ρ F b_k.
#include "lf/job/radiosity_solve.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

// Three unknowns in two groups ({0, 1}, {2}); unit areas. The chunks sweep exactly as
// lf::RadiositySweepChunks does: per group ||out - in|| and ||in|| in the power norm.
struct System {
    float rho = 0.5f;
    float f[3][3] = {{0, 0.5f, 0.5f}, {0.5f, 0, 0.5f}, {0.5f, 0.5f, 0}};
    Rgb e[3] = {Rgb(1, 1, 1), Rgb(0), Rgb(0)};
    std::vector<std::pair<int32_t, int32_t>> groups = {{0, 2}, {2, 3}};

    static double Power(const Rgb& c) { return std::abs(c.r) + std::abs(c.g) + std::abs(c.b); }

    SweepChunkResult Chunk(int sweep, int chunk, int chunks, const std::vector<Rgb>& b) const {
        // Groups split over chunks in order, evenly (lf::ChunkGroups tapers them; the sums do
        // not depend on where the chunks end).
        const int g0 = int(groups.size()) * chunk / chunks;
        const int g1 = int(groups.size()) * (chunk + 1) / chunks;
        SweepChunkResult r;
        r.sweep = sweep;
        r.chunk = chunk;
        r.sides = 3;
        r.side_begin = g0 < g1 ? groups[size_t(g0)].first : 0;
        for (int g = g0; g < g1; ++g) {
            double change = 0, power = 0;
            for (int i = groups[size_t(g)].first; i < groups[size_t(g)].second; ++i) {
                Rgb gathered(0);
                for (int j = 0; j < 3; ++j) gathered += b[size_t(j)] * f[i][j];
                const Rgb out = e[i] + gathered * rho;
                r.input.push_back(b[size_t(i)]);
                r.output.push_back(out);
                change += Power(out - b[size_t(i)]);
                power += Power(b[size_t(i)]);
            }
            r.change.push_back(change);
            r.power.push_back(power);
        }
        return r;
    }
};

// Runs the solve with `chunks` tasks per sweep, adding each sweep's results in `order`.
absl::StatusOr<RadiositySolve::Outcome> Solve(const System& s, int chunks,
                                              const std::vector<int>& order, double tolerance,
                                              int max_iterations) {
    RadiositySolve solve(chunks, tolerance, max_iterations);
    std::vector<Rgb> b(s.e, s.e + 3);
    for (;;) {
        for (int c : order) {
            if (absl::Status st = solve.Add(s.Chunk(solve.sweep(), c, chunks, b)); !st.ok()) {
                return st;
            }
        }
        EXPECT_TRUE(solve.SweepComplete());
        absl::StatusOr<RadiositySolve::Outcome> out = solve.FinishSweep();
        if (!out.ok() || out->converged) return out;
        b = out->radiosity;
    }
}

TEST(RadiositySolve, ConvergesToTheSolutionOfTheSystem) {
    // By symmetry b1 = b2 = x, b0 = y: y = 1 + 0.5 x and x = (y + x) / 4, so y = 3x, x = 0.4,
    // y = 1.2.
    const System s;
    absl::StatusOr<RadiositySolve::Outcome> out = Solve(s, 2, {0, 1}, 1e-6, 1000);
    ASSERT_TRUE(out.ok()) << out.status();
    EXPECT_TRUE(out->converged);
    EXPECT_NEAR(out->radiosity[0].r, 1.2, 1e-5);
    EXPECT_NEAR(out->radiosity[1].g, 0.4, 1e-5);
    EXPECT_NEAR(out->radiosity[2].b, 0.4, 1e-5);
    EXPECT_LE(out->residual, 1e-6);
    // The residual halves at most each sweep (ρ = 0.5): about log2(1e6) sweeps.
    EXPECT_GE(out->iterations, 15);
    EXPECT_LE(out->iterations, 40);
}

TEST(RadiositySolve, ArrivalOrderAndSplitDoNotChangeTheBits) {
    const System s;
    absl::StatusOr<RadiositySolve::Outcome> a = Solve(s, 2, {0, 1}, 1e-5, 1000);
    absl::StatusOr<RadiositySolve::Outcome> b = Solve(s, 2, {1, 0}, 1e-5, 1000);
    absl::StatusOr<RadiositySolve::Outcome> c = Solve(s, 4, {3, 1, 0, 2}, 1e-5, 1000);
    ASSERT_TRUE(a.ok() && b.ok() && c.ok());
    EXPECT_EQ(a->radiosity, b->radiosity);
    EXPECT_EQ(a->radiosity, c->radiosity);  // chunks 0 and 2 of 4 hold no group
    EXPECT_EQ(a->residual, c->residual);
    EXPECT_EQ(a->iterations, c->iterations);
}

TEST(RadiositySolve, IterationLimitFailsWithAReason) {
    absl::StatusOr<RadiositySolve::Outcome> out = Solve(System(), 2, {0, 1}, 1e-9, 5);
    ASSERT_EQ(out.status().code(), absl::StatusCode::kResourceExhausted);
    EXPECT_NE(out.status().message().find("not converged after 5 sweeps"), std::string::npos);
}

TEST(RadiositySolve, ADarkSceneIsSolvedAtOnce) {
    System s;
    s.e[0] = Rgb(0);
    absl::StatusOr<RadiositySolve::Outcome> out = Solve(s, 1, {0}, 1e-4, 10);
    ASSERT_TRUE(out.ok()) << out.status();
    EXPECT_TRUE(out->converged);
    EXPECT_EQ(out->iterations, 1);
    EXPECT_EQ(out->radiosity, std::vector<Rgb>(3, Rgb(0)));
}

TEST(RadiositySolve, RefusesResultsThatDoNotFit) {
    const System s;
    const std::vector<Rgb> e(s.e, s.e + 3);
    RadiositySolve solve(2, 1e-4, 100);
    EXPECT_EQ(solve.Add(s.Chunk(1, 0, 2, e)).code(), absl::StatusCode::kInvalidArgument);
    // Chunk 2 of 2 (AddressSanitizer found the test computing it past its groups' end).
    SweepChunkResult beyond = s.Chunk(0, 1, 2, e);
    beyond.chunk = 2;
    EXPECT_EQ(solve.Add(beyond).code(), absl::StatusCode::kInvalidArgument);
    ASSERT_TRUE(solve.Add(s.Chunk(0, 0, 2, e)).ok());
    EXPECT_EQ(solve.Add(s.Chunk(0, 0, 2, e)).code(), absl::StatusCode::kAlreadyExists);
    SweepChunkResult bigger = s.Chunk(0, 1, 2, e);
    bigger.sides = 4;
    EXPECT_EQ(solve.Add(bigger).code(), absl::StatusCode::kInvalidArgument);
    ASSERT_TRUE(solve.Add(s.Chunk(0, 1, 2, e)).ok());
    absl::StatusOr<RadiositySolve::Outcome> out = solve.FinishSweep();
    ASSERT_TRUE(out.ok());
    ASSERT_FALSE(out->converged);
    // Sweep 1 must read the server's b_1: a chunk swept from anything else is refused.
    EXPECT_EQ(solve.Add(s.Chunk(1, 0, 2, e)).code(), absl::StatusCode::kInvalidArgument);
    EXPECT_TRUE(solve.Add(s.Chunk(1, 0, 2, out->radiosity)).ok());
}

TEST(RadiositySolve, ChunksThatLeaveAGapAreRefused) {
    const System s;
    const std::vector<Rgb> e(s.e, s.e + 3);
    RadiositySolve solve(2, 1e-4, 100);
    ASSERT_TRUE(solve.Add(s.Chunk(0, 0, 2, e)).ok());
    SweepChunkResult shifted = s.Chunk(0, 1, 2, e);
    shifted.side_begin = 1;  // overlaps chunk 0 and leaves side 2 out
    ASSERT_TRUE(solve.Add(shifted).ok());
    EXPECT_EQ(solve.FinishSweep().status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
