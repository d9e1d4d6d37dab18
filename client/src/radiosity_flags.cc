#include "lf/client/radiosity_flags.h"

#include <limits>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/patch_mesh.h"
#include "lf/job/job_spec.h"

namespace lf {

namespace {
constexpr const char* kGroup = "Radiosity";

template <size_t N>
CLI::IsMember OneOf(const std::array<std::string_view, N>& names) {
    return CLI::IsMember(std::vector<std::string>(names.begin(), names.end()));
}
}  // namespace

void AddRadiosityFlags(CLI::App* cmd, RadiositySettings& settings) {
    const std::string group = kGroup;
    cmd->add_option("--patch-size", settings.patch_size,
                    "longest patch edge in scene units (overrides --patches)")
        ->group(group)
        ->check(CLI::Range(0.0, std::numeric_limits<double>::max()));
    cmd->add_option("--patches", settings.patches, "target number of patches")
        ->group(group)
        ->capture_default_str()
        ->check(CLI::Range(int64_t(1), kMaxPatchTarget));
    cmd->add_option("--max-patches", settings.max_patches,
                    "with --target-error: most patches mesh refinement may reach (0: 16 times "
                    "--patches)")
        ->group(group)
        ->capture_default_str()
        ->check(CLI::Range(int64_t(0), kMaxRefinedPatches));
    cmd->add_option("--radiosity", settings.form,
                    "flat: form factors between every pair of patches (n^2 time and memory, the "
                    "reference); hierarchical: links between clusters of patches, refined until "
                    "each carries at most --link-error of the scene's power (about linear in the "
                    "patches; solved by Jacobi sweeps)")
        ->group(group)
        ->capture_default_str()
        ->check(OneOf(kRadiosityForms));
    cmd->add_option("--link-error", settings.link_error,
                    "hierarchical: most power one link may carry, as a fraction of the power "
                    "the scene emits; smaller is closer to the flat solution and slower")
        ->group(group)
        ->capture_default_str()
        ->check(CLI::Range(kMinLinkError, kMaxLinkError));
    cmd->add_option("--solver", settings.solver,
                    "jacobi, gauss-seidel or shooting (--radiosity flat; hierarchical is jacobi)")
        ->group(group)
        ->capture_default_str()
        ->check(OneOf(kRadiositySolvers));
    cmd->add_option("--tolerance", settings.tolerance,
                    "stop when the relative residual (area-weighted L1) is below this")
        ->group(group)
        ->capture_default_str()
        ->check(CLI::Range(kMinTolerance, kMaxTolerance));
    cmd->add_option("--max-iterations", settings.max_iterations,
                    "fail if not converged after this many iterations")
        ->group(group)
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    cmd->add_option("--radiosity-display", settings.display,
                    "flat (one value per patch) or smooth (interpolated at vertices)")
        ->group(group)
        ->capture_default_str()
        ->check(OneOf(kRadiosityDisplays));
}

absl::Status CheckRadiosityFlagsApply(const CLI::App& cmd, const std::string& method) {
    if (method != "path") return absl::OkStatus();
    // Every option in the Radiosity group, the command's own (--sweep-tasks, --save-solution)
    // included.
    for (const CLI::Option* option : cmd.get_options()) {
        if (option->get_group() == kGroup && option->count() > 0) {
            return absl::InvalidArgumentError(
                absl::StrCat(option->get_name(),
                             " is a radiosity setting, but --method is "
                             "path: drop it, or use --method radiosity"));
        }
    }
    return absl::OkStatus();
}

}  // namespace lf
