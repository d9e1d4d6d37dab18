// Solving the radiosity system B = E + ρ ∘ (F B) for one RGB radiosity (W m^-2) per side.
//
// All solvers start from B = 0 or B = E and converge to the same B. They stop when the relative
// residual ||E + ρ F B - B|| / ||B|| of the returned B is below the tolerance, in the norm
// ||x|| = Σ_i A_i (|x_r| + |x_g| + |x_b|): power, so the residual is the fraction of the radiant
// power not yet accounted for. Each sweep shrinks the error by about max ρ (times the largest
// row sum, 1 in a closed scene), so a solve takes about ln(tolerance / (1 - ρ)) / ln(ρ) sweeps,
// and B is within about tolerance / (1 - ρ) of the solution.
//
// Jacobi and Gauss-Seidel are sequences of one pure step, GatherGroup: the new B of one group
// of sides from a solution so far. A Jacobi sweep applies it to every group against the same
// previous solution (in parallel); Gauss-Seidel applies the groups in order, each seeing the
// updates of those before it. Shooting (progressive refinement) sends the unshot radiosity of
// the group holding the most unshot power into the scene, one group at a time.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/rgb.h"
#include "lf/kernels/form_factors.h"

namespace lf {

enum class RadiositySolver { kJacobi, kGaussSeidel, kShooting };

// "jacobi", "gauss-seidel", "shooting".
absl::StatusOr<RadiositySolver> ParseRadiositySolver(std::string_view name);
const char* RadiositySolverName(RadiositySolver solver);

struct RadiositySystem {
    const FormFactors* form_factors = nullptr;
    // Per side: emitted exitance plus reflected direct light from point lights (W m^-2).
    std::vector<Rgb> emission;
    std::vector<Rgb> reflectance;
    std::vector<double> area;
};

struct SolveOptions {
    RadiositySolver solver = RadiositySolver::kGaussSeidel;
    double tolerance = 1e-4;
    // Sweeps; for shooting, shots adding up to this many sweeps' worth of form factors.
    int max_iterations = 10000;
    // Set from another thread: the solve returns Cancelled within one patch group's work.
    const std::atomic<bool>* cancel = nullptr;
};

struct SolveResult {
    std::vector<Rgb> radiosity;
    int iterations = 0;   // sweeps (Jacobi, Gauss-Seidel) or group shots (shooting)
    double sweeps = 0;    // form-factor work in units of one pass over the whole matrix
    double residual = 0;  // relative residual of `radiosity`, computed exactly
};

// InvalidArgument for negative or non-finite emission or reflectance, and for a reflectance of 1
// or more while the scene emits (no finite solution), naming the side. SolveRadiosity and the
// hierarchical solver check it before any work.
absl::Status CheckRadiosityValues(const RadiositySystem& system);

// Fails without iterating if a reflectance is 1 or more while there is emission (no finite
// solution), and if the iteration cap is reached first.
absl::StatusOr<SolveResult> SolveRadiosity(const RadiositySystem& system,
                                           const SolveOptions& options);

// The pure step: out[i - group.begin] = E_i + ρ_i Σ_j F_ij b_j for the sides i of `group`.
void GatherGroup(const RadiositySystem& system, int32_t group, std::span<const Rgb> b,
                 std::span<Rgb> out);

// GatherGroup, and the group's share of a Jacobi sweep's residual: change = ||out - b|| and
// power = ||b|| over the group's sides. A sweep sums these in group order, locally and on the
// farm alike (lf/job/radiosity_solve.h), so both stop after the same sweep with the same bits.
struct GroupSweep {
    double change = 0, power = 0;
};
GroupSweep JacobiGroup(const RadiositySystem& system, int32_t group, std::span<const Rgb> b,
                       std::span<Rgb> out);

// The power of radiosity c over `area` in that norm: area (|r| + |g| + |b|).
double RadiosityPower(double area, const Rgb& c);

// One Jacobi sweep: `next` from `b`, and the sweep's sums (stopping early, with meaningless sums,
// once `cancel` is set).
using JacobiStep = std::function<GroupSweep(std::span<const Rgb> b, std::span<Rgb> next,
                                            const std::atomic<bool>* cancel)>;
// The Jacobi solver's loop over any sweep (the flat one, the hierarchical one): sweeps from
// `emission` until a sweep's change / power is at most the tolerance; ResourceExhausted at the
// iteration limit, Cancelled soon after options.cancel is set.
absl::StatusOr<SolveResult> IterateJacobi(std::vector<Rgb> emission, const JacobiStep& step,
                                          const SolveOptions& options);

// ||E + ρ F b - b|| / ||b|| in the power norm above (0 when b and E are 0).
double RelativeResidual(const RadiositySystem& system, std::span<const Rgb> b);

// Progressive refinement: radiosity() after any number of shots is a lower bound of the
// solution; Preview() adds the ambient term (Cohen et al. 1988), the unshot power spread
// uniformly with the mean reflectance's interreflection factor, for an early look.
class ShootingSolver {
  public:
    explicit ShootingSolver(const RadiositySystem& system);

    void Shoot();             // the group with the most unshot power
    double residual() const;  // ||unshot|| / ||radiosity||, as tracked (not recomputed)
    int shots() const { return shots_; }
    double sweeps() const { return double(shot_entries_) / double(total_entries_); }

    std::vector<Rgb> Radiosity() const;
    std::vector<Rgb> Preview() const;

  private:
    struct Sum {
        double c[3] = {0, 0, 0};
    };
    void UpdateGroupPower(int32_t group);

    const RadiositySystem& system_;
    std::vector<Sum> radiosity_, unshot_;
    std::vector<double> group_unshot_power_;
    double radiosity_power_ = 0;
    int shots_ = 0;
    int64_t shot_entries_ = 0, total_entries_ = 1;
};

}  // namespace lf
