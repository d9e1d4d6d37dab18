// Solving the radiosity system B = E + ρ ∘ (F B) for one RGB radiosity (W m^-2) per side.
//
// All solvers start from B = 0 or B = E and converge to the same B. They stop when the relative
// residual ||E + ρ F B - B|| / ||B|| is below the tolerance (Jacobi: of the B its last sweep
// gathered from, one sweep before the B it returns), in the norm
// ||x|| = Σ_i A_i (|x_r| + |x_g| + |x_b|): power, so the residual is the fraction of the radiant
// power not yet accounted for. Each sweep shrinks the error by about max ρ (times the largest
// row sum, 1 in a closed scene), so a solve takes about ln(tolerance / (1 - ρ)) / ln(ρ) sweeps,
// and B is within about tolerance / (1 - ρ) of the solution.
//
// Jacobi and Gauss-Seidel are sequences of one pure step, GatherGroup: the irradiance H = F B
// one group of sides gathers from a solution so far, whose new radiosity is E + ρ H
// (RadiosityFromIrradiance). A Jacobi sweep applies it to every group against the same previous
// solution (in parallel); Gauss-Seidel applies the groups in order, each seeing the updates of
// those before it. Shooting (progressive refinement) sends the unshot radiosity of the group
// holding the most unshot power into the scene, one group at a time.
//
// Every solver returns the gathered irradiance with B: it is what the illuminance shows, and
// (B - E) / ρ cannot give it where a channel of ρ is 0.
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
    // Per side: the lights' direct irradiance (W m^-2), which `emission` holds reflected. The
    // solvers do not read it; the display adds it to the gathered irradiance. Empty where no one
    // needs it (hand-made systems, the hierarchy's copy in tree order).
    std::vector<Rgb> direct;
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
    // Per side, F B gathered from the other sides (W m^-2; the lights' direct irradiance is not
    // in it). Jacobi and Gauss-Seidel: radiosity = E + ρ irradiance exactly; shooting: F of its
    // radiosity. Jacobi's `residual` is that of the radiosity its last sweep gathered from.
    std::vector<Rgb> irradiance;
    int iterations = 0;  // sweeps (Jacobi, Gauss-Seidel) or group shots (shooting)
    double sweeps = 0;   // form-factor work in units of one pass over the whole matrix
    // Relative residual, computed exactly: of `radiosity`, except Jacobi's (above).
    double residual = 0;
};

// InvalidArgument for negative or non-finite emission or reflectance, and for a reflectance of 1
// or more while the scene emits (no finite solution), naming the side. SolveRadiosity and the
// hierarchical solver check it before any work.
absl::Status CheckRadiosityValues(const RadiositySystem& system);

// Fails without iterating if a reflectance is 1 or more while there is emission (no finite
// solution), and if the iteration cap is reached first.
absl::StatusOr<SolveResult> SolveRadiosity(const RadiositySystem& system,
                                           const SolveOptions& options);

// A side's radiosity E + ρ H from the irradiance H it gathered, in double and rounded once: the
// one formula of the solvers, the farm's sweeps and the display, so all have the same bits.
inline Rgb RadiosityFromIrradiance(const Rgb& emission, const Rgb& reflectance, const Rgb& h) {
    return Rgb(float(double(emission.r) + double(reflectance.r) * h.r),
               float(double(emission.g) + double(reflectance.g) * h.g),
               float(double(emission.b) + double(reflectance.b) * h.b));
}
// That for every side of `system`.
std::vector<Rgb> RadiosityFromIrradiance(const RadiositySystem& system,
                                         std::span<const Rgb> irradiance);

// The pure step: out[i - group.begin] = Σ_j F_ij b_j, the irradiance the sides i of `group`
// gather from radiosity b.
void GatherGroup(const FormFactors& form_factors, int32_t group, std::span<const Rgb> b,
                 std::span<Rgb> out);

// A group's share of a Jacobi sweep's residual, with `gathered` the new irradiance of its sides
// from `begin` on: change = ||B_new - b|| (B_new = E + ρ gathered) and power = ||b|| over them. A
// sweep sums these in group order, locally and on the farm alike (lf/job/radiosity_solve.h), so
// both stop after the same sweep with the same bits.
struct GroupSweep {
    double change = 0, power = 0;
};
GroupSweep SweepSums(const RadiositySystem& system, int32_t begin, std::span<const Rgb> b,
                     std::span<const Rgb> gathered);
// GatherGroup with `form_factors` (the system's, or a farm chunk's rows), and its SweepSums.
GroupSweep JacobiGroup(const RadiositySystem& system, const FormFactors& form_factors,
                       int32_t group, std::span<const Rgb> b, std::span<Rgb> out);

// The power of radiosity c over `area` in that norm: area (|r| + |g| + |b|).
double RadiosityPower(double area, const Rgb& c);

// One Jacobi sweep: the irradiance `gathered` from radiosity `b`, and the sweep's sums (stopping
// early, with meaningless sums, once `cancel` is set).
using JacobiStep = std::function<GroupSweep(std::span<const Rgb> b, std::span<Rgb> gathered,
                                            const std::atomic<bool>* cancel)>;
// The Jacobi solver's loop over any sweep (the flat one, the hierarchical one) of `system` (its
// E and ρ): from no gathered irradiance (B = E), each sweep gathers H from B = E + ρ H of the
// last, until a sweep's change / power is at most the tolerance. The result is that sweep's H
// and its B = E + ρ H, so H is all a black side receives from the radiosity the residual was
// measured on; that B, one sweep on, is closer still (from E, Jacobi rises monotonically to the
// solution). Zero at once when nothing emits; ResourceExhausted at the iteration limit,
// Cancelled soon after options.cancel is set.
absl::StatusOr<SolveResult> IterateJacobi(const RadiositySystem& system, const JacobiStep& step,
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
