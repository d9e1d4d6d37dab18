// The farm's radiosity solve, without I/O: Jacobi sweeps, each split into patch-group tasks
// (chunks of the patch groups, see lf::RadiositySweepChunk), until the relative residual is
// below the tolerance. The state is the irradiance each side gathered, H_k (B_k = E + ρ H_k):
// sweep k's tasks all read H_k (sweep 0: zero, which the workers start from) and each returns
// its chunk's H_{k+1} and residual sums (of B, ||B_{k+1} - B_k|| and ||B_k||). The sums are
// added in group order and the stop follows SolveRadiosity's Jacobi solver exactly, so the
// solution has the bits of `lightfarm render --method radiosity --solver jacobi`.
//
// Jacobi, because its sweep splits into independent tasks; Gauss-Seidel and shooting update
// one group after another, so they would run one task at a time.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/radiosity_codec.h"
#include "lf/core/rgb.h"

namespace lf {

class RadiositySolve {
  public:
    RadiositySolve(int chunks, double tolerance, int max_iterations);

    int chunks() const { return chunks_; }
    int sweep() const { return sweep_; }  // the sweep whose tasks are out

    // Chunks' results of the current sweep (one task's), all or none. InvalidArgument when one
    // is of another sweep or chunk count, or does not fit the results before it or beside it
    // (system size, sides covered, input); AlreadyExists for a chunk added before or twice.
    absl::Status Add(std::span<const SweepChunkResult> results);
    absl::Status Add(const SweepChunkResult& result) { return Add({&result, 1}); }
    bool SweepComplete() const;

    struct Outcome {
        bool converged = false;  // radiosity is the solution; else the next sweep's input
        // The gathered irradiance H_{k+1} (RadiosityRendererFor turns a solution into B and the
        // irradiance), named for the blob it travels in.
        std::vector<Rgb> radiosity;
        double residual = 0;  // of the sweep's input
        int iterations = 0;
    };
    // Once SweepComplete(): the next sweep's input, or the solution. ResourceExhausted when the
    // iteration limit is reached first. Starts the next sweep.
    absl::StatusOr<Outcome> FinishSweep();

  private:
    // Whether `result` fits the results added before.
    absl::Status Check(const SweepChunkResult& result) const;

    int chunks_;
    double tolerance_;
    int max_iterations_;
    int sweep_ = 0;
    std::vector<std::optional<SweepChunkResult>> results_;  // by chunk, this sweep
    std::vector<Rgb> input_;                                // H of this sweep, once known
};

}  // namespace lf
