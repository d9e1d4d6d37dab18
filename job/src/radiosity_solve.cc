#include "lf/job/radiosity_solve.h"

#include "absl/strings/str_format.h"

namespace lf {

RadiositySolve::RadiositySolve(int chunks, double tolerance, int max_iterations)
    : chunks_(chunks), tolerance_(tolerance), max_iterations_(max_iterations), results_(chunks) {}

absl::Status RadiositySolve::Add(std::span<const SweepChunkResult> results) {
    for (size_t k = 0; k < results.size(); ++k) {
        const SweepChunkResult& r = results[k];
        if (absl::Status s = Check(r); !s.ok()) return s;
        for (size_t j = 0; j < k; ++j) {
            if (results[j].chunk == r.chunk) {
                return absl::AlreadyExistsError(
                    absl::StrFormat("sweep %d chunk %d twice in one result", r.sweep, r.chunk));
            }
            if (results[j].sides != r.sides) {
                return absl::InvalidArgumentError(
                    absl::StrFormat("sweep result of chunk %d has %d unknowns, chunk %d had %d",
                                    r.chunk, r.sides, results[j].chunk, results[j].sides));
            }
        }
    }
    for (const SweepChunkResult& r : results) results_[size_t(r.chunk)] = r;
    return absl::OkStatus();
}

absl::Status RadiositySolve::Check(const SweepChunkResult& r) const {
    if (r.sweep != sweep_ || r.chunk < 0 || r.chunk >= chunks_) {
        return absl::InvalidArgumentError(
            absl::StrFormat("sweep result of sweep %d chunk %d, expected sweep %d chunk 0..%d",
                            r.sweep, r.chunk, sweep_, chunks_ - 1));
    }
    if (results_[size_t(r.chunk)]) {
        return absl::AlreadyExistsError(
            absl::StrFormat("sweep %d chunk %d was merged before", r.sweep, r.chunk));
    }
    if (r.change.size() != r.power.size() || r.input.size() != r.output.size()) {
        return absl::InvalidArgumentError("sweep result: inconsistent lengths");
    }
    for (const auto& other : results_) {
        if (other && other->sides != r.sides) {
            return absl::InvalidArgumentError(
                absl::StrFormat("sweep result of chunk %d has %d unknowns, chunk %d had %d",
                                r.chunk, r.sides, other->chunk, other->sides));
        }
    }
    if (!input_.empty()) {
        if (int64_t(input_.size()) != r.sides) {
            return absl::InvalidArgumentError("sweep result: the system changed size");
        }
        // The input is the server's own state: a worker that swept something else is wrong.
        for (size_t i = 0; i < r.input.size(); ++i) {
            if (!(r.input[i] == input_[size_t(r.side_begin) + i])) {
                return absl::InvalidArgumentError(absl::StrFormat(
                    "sweep %d chunk %d: swept a radiosity other than the sweep's input", r.sweep,
                    r.chunk));
            }
        }
    }
    return absl::OkStatus();
}

bool RadiositySolve::SweepComplete() const {
    for (const auto& r : results_) {
        if (!r) return false;
    }
    return true;
}

absl::StatusOr<RadiositySolve::Outcome> RadiositySolve::FinishSweep() {
    // The chunks must tile [0, sides) in order: then group order is chunk order.
    const int32_t sides = results_[0]->sides;
    std::vector<Rgb> output(static_cast<size_t>(sides));
    int32_t next_side = 0;
    double change = 0, power = 0;
    for (const auto& r : results_) {
        if (r->input.empty()) continue;
        if (r->side_begin != next_side) {
            return absl::InvalidArgumentError(
                absl::StrFormat("sweep %d: chunk %d starts at side %d, expected %d", sweep_,
                                r->chunk, r->side_begin, next_side));
        }
        std::copy(r->output.begin(), r->output.end(), output.begin() + r->side_begin);
        next_side += int32_t(r->input.size());
        for (size_t g = 0; g < r->change.size(); ++g) {
            change += r->change[g];
            power += r->power[g];
        }
    }
    if (next_side != sides) {
        return absl::InvalidArgumentError(
            absl::StrFormat("sweep %d: the chunks cover %d of %d sides", sweep_, next_side, sides));
    }
    Outcome out;
    out.iterations = sweep_ + 1;
    // No power at all: the scene is dark and E (zero) is the solution, as SolveRadiosity says.
    out.residual = power > 0 ? change / power : 0;
    out.converged = power == 0 || out.residual <= tolerance_;
    if (!out.converged && out.iterations >= max_iterations_) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "radiosity: not converged after %d sweeps (relative residual %.3g > tolerance %.3g): "
            "raise the iteration limit or the tolerance",
            out.iterations, out.residual, tolerance_));
    }
    // Converged or not, the gathered irradiance of this sweep is the next state (IterateJacobi).
    out.radiosity = output;
    input_ = std::move(output);
    ++sweep_;
    results_.assign(size_t(chunks_), std::nullopt);
    return out;
}

}  // namespace lf
