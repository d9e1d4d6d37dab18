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
    cmd->add_option("--noise-threshold", settings.noise_threshold,
                    "per-pixel adaptive sampling as Cycles' Noise Threshold (the same error "
                    "measure and scale, e.g. 0.01): a pixel stops once Cycles' error of its "
                    "A/B halves is below 5x this; --spp is its minimum samples (default: Cycles' "
                    "automatic ceil(16 / T^0.3): 0.1 -> 32, 0.01 -> 64; at least 4), --max-spp its "
                    "most (default 65536: pixels that never converge, such as caustic "
                    "fireflies, go that far unless --max-spp or --time-limit says less; Cycles' "
                    "Max Samples defaults to 4096). Not with --target-error")
        ->group(a)
        ->check(CLI::Range(kMinNoiseThreshold, 1.0));
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

void ApplyNoiseThresholdMinSpp(const CLI::App& cmd, const AdaptiveSettings& settings,
                               uint64_t& spp) {
    if (settings.noise_threshold > 0 && cmd.count("--spp") == 0) {
        spp = NoiseThresholdMinSpp(settings.noise_threshold);
    }
}

}  // namespace lf
