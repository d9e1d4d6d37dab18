#include "lf/client/adaptive_flags.h"

#include "lf/job/job_spec.h"
#include "lf/job/plan.h"

namespace lf {

void AddAdaptiveFlags(CLI::App* cmd, AdaptiveSettings& settings) {
    const std::string a = "Adaptive sampling (docs/convergence.md)";
    cmd->add_option("--target-error", settings.target_error,
                    "stop sampling a tile once its estimated relative error (from the A/B "
                    "halves) is at most this, e.g. 0.01; --spp is then the first pass. With "
                    "--method radiosity, also refine the mesh until its estimated "
                    "discretisation error is at most this (docs/radiosity.md)")
        ->group(a)
        ->check(CLI::Range(kMinTargetError, kMaxTargetError));
    cmd->add_option("--time-limit", settings.time_limit,
                    "stop sampling about this many seconds after the render starts (every tile "
                    "gets its first pass); alone, tiles double their samples until then")
        ->group(a)
        ->check(CLI::Range(kMinTimeLimit, kMaxTimeLimit));
    cmd->add_option("--max-spp", settings.max_spp, "most samples per pixel of an adaptive render")
        ->group(a)
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(2), kMaxSpp));
}

}  // namespace lf
