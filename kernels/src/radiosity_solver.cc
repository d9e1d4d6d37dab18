#include "lf/kernels/radiosity_solver.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "lf/core/cancel.h"
#include "lf/core/log.h"

namespace lf {

namespace {

double SystemPower(const RadiositySystem& system, std::span<const Rgb> b) {
    double power = 0;
    for (size_t i = 0; i < b.size(); ++i) power += RadiosityPower(system.area[i], b[i]);
    return power;
}

// Nothing emits: no light anywhere, and no sweeps (whose relative residual would be 0 / 0).
SolveResult Dark(const RadiositySystem& system) {
    SolveResult dark;
    dark.radiosity.assign(system.emission.size(), Rgb(0));
    dark.irradiance = dark.radiosity;
    return dark;
}

double Relative(const GroupSweep& sweep) {
    return sweep.power > 0 ? sweep.change / sweep.power : sweep.change;
}

absl::Status Validate(const RadiositySystem& system) {
    const size_t n = system.emission.size();
    if (!system.form_factors || system.form_factors->size() != int32_t(n) ||
        system.reflectance.size() != n || system.area.size() != n) {
        return absl::InvalidArgumentError("radiosity: inconsistent system sizes");
    }
    return CheckRadiosityValues(system);
}

}  // namespace

absl::Status CheckRadiosityValues(const RadiositySystem& system) {
    const size_t n = system.emission.size();
    bool emission = false;
    int32_t bright = -1;
    for (size_t i = 0; i < n; ++i) {
        const Rgb &e = system.emission[i], &rho = system.reflectance[i];
        if (!e.IsFinite() || !rho.IsFinite() || std::min({e.r, e.g, e.b}) < 0 ||
            std::min({rho.r, rho.g, rho.b}) < 0) {
            return absl::InvalidArgumentError(absl::StrCat(
                "radiosity: negative or non-finite emission or reflectance at side ", i));
        }
        emission |= !e.IsBlack();
        if (bright < 0 && rho.MaxComponent() >= 1) bright = int32_t(i);
    }
    if (emission && bright >= 0) {
        const Rgb& rho = system.reflectance[size_t(bright)];
        return absl::InvalidArgumentError(absl::StrFormat(
            "radiosity: reflectance (%g, %g, %g) at side %d is 1 or more while the scene emits: "
            "light would never be absorbed and the radiosity equation has no finite solution",
            rho.r, rho.g, rho.b, bright));
    }
    return absl::OkStatus();
}

namespace {

absl::Status NotConverged(int sweeps, double residual, double tolerance) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "radiosity: not converged after %d sweeps (relative residual %.3g > tolerance %.3g); "
        "reflectance near 1 needs about ln(tolerance / (1 - reflectance)) / ln(reflectance) "
        "sweeps: raise the iteration limit or the tolerance",
        sweeps, residual, tolerance));
}

// At most one progress line every few seconds, none for quick solves.
class SolveLog {
  public:
    void Maybe(const char* what, int count, double residual) {
        const auto now = std::chrono::steady_clock::now();
        if (now < next_) return;
        next_ = now + std::chrono::seconds(5);
        NamedLogger("radiosity")->info("{} {}: relative residual {:.3g}", what, count, residual);
    }

  private:
    std::chrono::steady_clock::time_point next_ =
        std::chrono::steady_clock::now() + std::chrono::seconds(5);
};

absl::Status SolveCancelled() { return absl::CancelledError("radiosity: solve cancelled"); }

// The irradiance F b every group gathers, at once, and the sweep's residual sums. Once `cancel`
// is set the remaining groups are skipped (the sums are then meaningless).
GroupSweep JacobiSweep(const RadiositySystem& system, std::span<const Rgb> b,
                       std::span<Rgb> gathered, const std::atomic<bool>* cancel = nullptr) {
    const auto& groups = system.form_factors->groups();
    std::vector<GroupSweep> parts(groups.size());
    tbb::parallel_for(size_t(0), groups.size(), [&](size_t g) {
        if (CancelRequested(cancel)) return;
        const PatchGroup& group = groups[g];
        parts[g] = JacobiGroup(system, *system.form_factors, int32_t(g), b,
                               gathered.subspan(size_t(group.begin), size_t(group.size())));
    });
    GroupSweep total;
    for (const GroupSweep& p : parts) {
        total.change += p.change;
        total.power += p.power;
    }
    return total;
}

}  // namespace

absl::StatusOr<SolveResult> IterateJacobi(const RadiositySystem& system, const JacobiStep& step,
                                          const SolveOptions& options) {
    if (SystemPower(system, system.emission) == 0) return Dark(system);
    SolveResult result;
    const size_t n = system.emission.size();
    std::vector<Rgb> h(n), next(n), b = system.emission;  // nothing gathered yet
    SolveLog log;
    for (;;) {
        const GroupSweep sweep = step(b, next, options.cancel);
        if (CancelRequested(options.cancel)) return SolveCancelled();
        const double residual = sweep.change / sweep.power;
        ++result.iterations;
        h.swap(next);
        b = RadiosityFromIrradiance(system, h);
        if (residual <= options.tolerance) {
            result.residual = residual;
            break;
        }
        if (result.iterations >= options.max_iterations) {
            return NotConverged(result.iterations, residual, options.tolerance);
        }
        log.Maybe("jacobi sweep", result.iterations, residual);
    }
    result.sweeps = result.iterations;
    result.radiosity = std::move(b);
    result.irradiance = std::move(h);
    return result;
}

namespace {

absl::StatusOr<SolveResult> SolveJacobi(const RadiositySystem& system,
                                        const SolveOptions& options) {
    return IterateJacobi(
        system,
        [&](std::span<const Rgb> b, std::span<Rgb> gathered, const std::atomic<bool>* cancel) {
            return JacobiSweep(system, b, gathered, cancel);
        },
        options);
}

// Gauss-Seidel converges monotonically from below (E, ρ, F >= 0), so a sweep's change bounds
// the residual of the solution it started from; the exact residual confirms the stop. Each
// side keeps the irradiance its last update gathered, so B = E + ρ H holds side by side.
absl::StatusOr<SolveResult> SolveGaussSeidel(const RadiositySystem& system,
                                             const SolveOptions& options) {
    SolveResult result;
    std::vector<Rgb> b = system.emission, h(b.size());
    const auto& groups = system.form_factors->groups();
    SolveLog log;
    for (;;) {
        double change = 0;
        for (size_t g = 0; g < groups.size(); ++g) {
            if (CancelRequested(options.cancel)) return SolveCancelled();
            const PatchGroup& group = groups[g];
            const std::span<Rgb> gathered(&h[size_t(group.begin)], size_t(group.size()));
            GatherGroup(*system.form_factors, int32_t(g), b, gathered);
            for (int32_t i = group.begin; i < group.end; ++i) {
                Rgb& bi = b[size_t(i)];
                const Rgb ui = RadiosityFromIrradiance(system.emission[size_t(i)],
                                                       system.reflectance[size_t(i)], h[size_t(i)]);
                change += RadiosityPower(system.area[size_t(i)], ui - bi);
                bi = ui;
            }
        }
        ++result.iterations;
        ++result.sweeps;
        const double estimate = change / SystemPower(system, b);
        if (estimate <= options.tolerance) {
            result.residual = RelativeResidual(system, b);
            ++result.sweeps;
            if (result.residual <= options.tolerance) break;
        }
        if (result.iterations >= options.max_iterations) {
            return NotConverged(result.iterations, estimate, options.tolerance);
        }
        log.Maybe("gauss-seidel sweep", result.iterations, estimate);
    }
    result.radiosity = std::move(b);
    result.irradiance = std::move(h);
    return result;
}

// The tracked residual drifts from the exact one by rounding, so a stop is confirmed exactly, by
// the sweep that also gathers the irradiance of the result.
absl::StatusOr<SolveResult> SolveShooting(const RadiositySystem& system,
                                          const SolveOptions& options) {
    ShootingSolver shooter(system);
    SolveLog log;
    SolveResult result;
    int exact_checks = 0;
    for (;;) {
        if (CancelRequested(options.cancel)) return SolveCancelled();
        if (shooter.residual() <= options.tolerance) {
            result.radiosity = shooter.Radiosity();
            result.irradiance.resize(result.radiosity.size());
            result.residual = Relative(JacobiSweep(system, result.radiosity, result.irradiance));
            ++exact_checks;
            if (result.residual <= options.tolerance) break;
        }
        if (shooter.sweeps() >= options.max_iterations) {
            return NotConverged(int(shooter.sweeps()), shooter.residual(), options.tolerance);
        }
        shooter.Shoot();
        log.Maybe("shot", shooter.shots(), shooter.residual());
    }
    result.iterations = shooter.shots();
    result.sweeps = shooter.sweeps() + exact_checks;
    return result;
}

}  // namespace

double RadiosityPower(double area, const Rgb& c) {
    return area * (double(std::abs(c.r)) + std::abs(c.g) + std::abs(c.b));
}

absl::StatusOr<RadiositySolver> ParseRadiositySolver(std::string_view name) {
    for (RadiositySolver s :
         {RadiositySolver::kJacobi, RadiositySolver::kGaussSeidel, RadiositySolver::kShooting}) {
        if (name == RadiositySolverName(s)) return s;
    }
    return absl::InvalidArgumentError(
        absl::StrCat("unknown radiosity solver '", std::string(name),
                     "' (expected jacobi, gauss-seidel or shooting)"));
}

const char* RadiositySolverName(RadiositySolver solver) {
    switch (solver) {
        case RadiositySolver::kJacobi:
            return "jacobi";
        case RadiositySolver::kGaussSeidel:
            return "gauss-seidel";
        case RadiositySolver::kShooting:
            return "shooting";
    }
    return "unknown";
}

void GatherGroup(const FormFactors& form_factors, int32_t group, std::span<const Rgb> b,
                 std::span<Rgb> out) {
    const PatchGroup& g = form_factors.groups()[size_t(group)];
    std::vector<double> sum(size_t(g.size()) * 3, 0.0);
    for (const FormFactorBlock& block : form_factors.RowBlocks(group)) {
        const int32_t cols = block.cols();
        const Rgb* source = &b[size_t(block.col_begin)];
        for (int32_t r = block.row_begin; r < block.row_end; ++r) {
            const float* f = &block.values[size_t(r - block.row_begin) * size_t(cols)];
            double s0 = 0, s1 = 0, s2 = 0;
            for (int32_t c = 0; c < cols; ++c) {
                s0 += double(f[c]) * source[c].r;
                s1 += double(f[c]) * source[c].g;
                s2 += double(f[c]) * source[c].b;
            }
            double* acc = &sum[size_t(r - g.begin) * 3];
            acc[0] += s0;
            acc[1] += s1;
            acc[2] += s2;
        }
    }
    for (size_t i = 0; i < size_t(g.size()); ++i) {
        out[i] = Rgb(float(sum[i * 3]), float(sum[i * 3 + 1]), float(sum[i * 3 + 2]));
    }
}

std::vector<Rgb> RadiosityFromIrradiance(const RadiositySystem& system,
                                         std::span<const Rgb> irradiance) {
    std::vector<Rgb> b(irradiance.size());
    for (size_t i = 0; i < b.size(); ++i) {
        b[i] = RadiosityFromIrradiance(system.emission[i], system.reflectance[i], irradiance[i]);
    }
    return b;
}

GroupSweep SweepSums(const RadiositySystem& system, int32_t begin, std::span<const Rgb> b,
                     std::span<const Rgb> gathered) {
    GroupSweep sums;
    for (size_t k = 0; k < gathered.size(); ++k) {
        const size_t i = size_t(begin) + k;
        const Rgb next =
            RadiosityFromIrradiance(system.emission[i], system.reflectance[i], gathered[k]);
        sums.change += RadiosityPower(system.area[i], next - b[i]);
        sums.power += RadiosityPower(system.area[i], b[i]);
    }
    return sums;
}

GroupSweep JacobiGroup(const RadiositySystem& system, const FormFactors& form_factors,
                       int32_t group, std::span<const Rgb> b, std::span<Rgb> out) {
    GatherGroup(form_factors, group, b, out);
    return SweepSums(system, form_factors.groups()[size_t(group)].begin, b, out);
}

double RelativeResidual(const RadiositySystem& system, std::span<const Rgb> b) {
    std::vector<Rgb> gathered(b.size());
    return Relative(JacobiSweep(system, b, gathered));
}

absl::StatusOr<SolveResult> SolveRadiosity(const RadiositySystem& system,
                                           const SolveOptions& options) {
    if (absl::Status status = Validate(system); !status.ok()) return status;
    if (!(options.tolerance > 0) || options.max_iterations < 1) {
        return absl::InvalidArgumentError("radiosity: tolerance and iteration limit must be > 0");
    }
    if (SystemPower(system, system.emission) == 0) return Dark(system);
    switch (options.solver) {
        case RadiositySolver::kJacobi:
            return SolveJacobi(system, options);
        case RadiositySolver::kGaussSeidel:
            return SolveGaussSeidel(system, options);
        case RadiositySolver::kShooting:
            return SolveShooting(system, options);
    }
    return absl::InvalidArgumentError("radiosity: unknown solver");
}

// Shooting -------------------------------------------------------------------------------------

ShootingSolver::ShootingSolver(const RadiositySystem& system)
    : system_(system),
      radiosity_(system.emission.size()),
      unshot_(system.emission.size()),
      group_unshot_power_(system.form_factors->groups().size(), 0) {
    for (size_t i = 0; i < unshot_.size(); ++i) {
        for (int c = 0; c < 3; ++c) unshot_[i].c[c] = system.emission[i][c];
    }
    for (int32_t g = 0; g < int32_t(group_unshot_power_.size()); ++g) UpdateGroupPower(g);
    total_entries_ = 0;
    for (const FormFactorBlock& block : system.form_factors->blocks()) {
        total_entries_ += int64_t(block.values.size());
    }
    total_entries_ = std::max<int64_t>(total_entries_, 1);
}

void ShootingSolver::UpdateGroupPower(int32_t group) {
    const PatchGroup& g = system_.form_factors->groups()[size_t(group)];
    double power = 0;
    for (int32_t i = g.begin; i < g.end; ++i) {
        const Sum& u = unshot_[size_t(i)];
        power += system_.area[size_t(i)] * (std::abs(u.c[0]) + std::abs(u.c[1]) + std::abs(u.c[2]));
    }
    group_unshot_power_[size_t(group)] = power;
}

double ShootingSolver::residual() const {
    double unshot = 0;
    for (double p : group_unshot_power_) unshot += p;
    if (radiosity_power_ == 0) return unshot > 0 ? 1 : 0;
    return unshot / radiosity_power_;
}

void ShootingSolver::Shoot() {
    const FormFactors& ff = *system_.form_factors;
    const int32_t shooter =
        int32_t(std::max_element(group_unshot_power_.begin(), group_unshot_power_.end()) -
                group_unshot_power_.begin());
    const PatchGroup& g = ff.groups()[size_t(shooter)];
    std::vector<Sum> shot(unshot_.begin() + g.begin, unshot_.begin() + g.end);
    for (int32_t i = g.begin; i < g.end; ++i) {
        Sum& b = radiosity_[size_t(i)];
        for (int c = 0; c < 3; ++c) b.c[c] += unshot_[size_t(i)].c[c];
        radiosity_power_ +=
            system_.area[size_t(i)] *
            (unshot_[size_t(i)].c[0] + unshot_[size_t(i)].c[1] + unshot_[size_t(i)].c[2]);
        unshot_[size_t(i)] = Sum();
    }
    // Each block of the shooter's columns belongs to a different receiving group.
    const std::span<const int32_t> blocks = ff.ColumnBlocks(shooter);
    tbb::parallel_for(size_t(0), blocks.size(), [&](size_t k) {
        const FormFactorBlock& block = ff.blocks()[size_t(blocks[k])];
        const int32_t cols = block.cols();
        const Sum* source = &shot[size_t(block.col_begin - g.begin)];
        for (int32_t r = block.row_begin; r < block.row_end; ++r) {
            const float* f = &block.values[size_t(r - block.row_begin) * size_t(cols)];
            double s[3] = {0, 0, 0};
            for (int32_t c = 0; c < cols; ++c) {
                for (int ch = 0; ch < 3; ++ch) s[ch] += double(f[c]) * source[c].c[ch];
            }
            const Rgb& rho = system_.reflectance[size_t(r)];
            for (int ch = 0; ch < 3; ++ch) unshot_[size_t(r)].c[ch] += rho[ch] * s[ch];
        }
        UpdateGroupPower(block.row_group);
    });
    UpdateGroupPower(shooter);
    for (int32_t b : blocks) shot_entries_ += int64_t(ff.blocks()[size_t(b)].values.size());
    ++shots_;
}

std::vector<Rgb> ShootingSolver::Radiosity() const {
    std::vector<Rgb> b(radiosity_.size());
    for (size_t i = 0; i < b.size(); ++i) {
        b[i] = Rgb(float(radiosity_[i].c[0]), float(radiosity_[i].c[1]), float(radiosity_[i].c[2]));
    }
    return b;
}

std::vector<Rgb> ShootingSolver::Preview() const {
    double area = 0, unshot[3] = {0, 0, 0}, rho[3] = {0, 0, 0};
    for (size_t i = 0; i < radiosity_.size(); ++i) {
        const double a = system_.area[i];
        area += a;
        for (int c = 0; c < 3; ++c) {
            unshot[c] += a * unshot_[i].c[c];
            rho[c] += a * system_.reflectance[i][c];
        }
    }
    std::vector<Rgb> b = Radiosity();
    if (area == 0) return b;
    Rgb ambient;
    for (int c = 0; c < 3; ++c) {
        const double mean_rho = std::min(rho[c] / area, 0.999);
        ambient[c] = float(unshot[c] / area / (1 - mean_rho));
    }
    for (size_t i = 0; i < b.size(); ++i) b[i] += system_.reflectance[i] * ambient;
    return b;
}

}  // namespace lf
