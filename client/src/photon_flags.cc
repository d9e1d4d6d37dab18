#include "lf/client/photon_flags.h"

#include "absl/strings/str_cat.h"

namespace lf {

namespace {

constexpr const char* kPhotonFlags[] = {"--photons", "--ppm-radius", "--ppm-alpha"};

}  // namespace

void AddPhotonFlags(CLI::App* cmd, PhotonSettings& settings) {
    const std::string group = "Photon mapping (--method ppm)";
    cmd->add_option("--photons", settings.photons_per_pass,
                    "photons traced per pass; each pass is an independent photon map gathered at "
                    "one camera sample per pixel, and --spp sets the passes")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), kMaxPhotonsPerPass))
        ->group(group);
    cmd->add_option("--ppm-radius", settings.initial_radius,
                    "gather radius of the first pass, in scene units; 0 = chosen from the "
                    "scene's size and the frame. Larger: less noise, more blur (bias) early on")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e30))
        ->group(group);
    cmd->add_option("--ppm-alpha", settings.alpha,
                    "radius schedule r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1) (Knaus and Zwicker "
                    "2011), in (0, 1): after N passes the bias falls as N^(alpha - 1) and the "
                    "variance as N^-alpha, so a larger alpha trades bias for less noise")
        ->capture_default_str()
        ->check([](const std::string& text) -> std::string {
            double a = 0;
            if (!CLI::detail::lexical_cast(text, a) || !(a > 0 && a < 1)) {
                return absl::StrCat("--ppm-alpha ", text, ": expected above 0 and below 1");
            }
            return "";
        })
        ->group(group);
}

absl::Status CheckPhotonFlagsApply(const CLI::App& cmd, const std::string& method) {
    if (method == "ppm") return absl::OkStatus();
    for (const char* flag : kPhotonFlags) {
        if (cmd.count(flag) > 0) {
            return absl::InvalidArgumentError(
                absl::StrCat(flag, " is a photon mapping setting, but --method is ", method,
                             ": drop it, or use --method ppm"));
        }
    }
    return absl::OkStatus();
}

}  // namespace lf
