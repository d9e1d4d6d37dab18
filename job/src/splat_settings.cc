#include "lf/job/splat_settings.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"
#include "lf/job/method_registry.h"

namespace lf {

absl::Status CheckPhotonSettings(const PhotonSettings& ppm) {
    if (ppm.photons_per_pass < 1 || ppm.photons_per_pass > kMaxPhotonsPerPass) {
        return absl::InvalidArgumentError(absl::StrCat(
            "ppm.photons_per_pass ", ppm.photons_per_pass, ": expected 1 to ", kMaxPhotonsPerPass));
    }
    // Finite: an infinite radius gathers every photon of the scene at every pixel.
    if (!(ppm.initial_radius >= 0) || !std::isfinite(ppm.initial_radius)) {
        return absl::InvalidArgumentError(
            absl::StrCat("ppm.initial_radius ", ppm.initial_radius,
                         ": expected a finite radius >= 0 (0: the kernel's choice)"));
    }
    // alpha = 1 never shrinks the radius (the bias never falls); 0 shrinks it to nothing at once.
    if (!(ppm.alpha > 0 && ppm.alpha < 1)) {
        return absl::InvalidArgumentError(
            absl::StrCat("ppm.alpha ", ppm.alpha, ": expected above 0 and below 1"));
    }
    return absl::OkStatus();
}

std::optional<SplatPlanKind> SplatPlanKindOf(std::string_view method) {
    const std::optional<Method> m = FindMethod(method);
    return m ? Info(*m).splat_plan : std::nullopt;
}

absl::StatusOr<SplatPlanSettings> SplatPlanSettingsOf(std::string_view method,
                                                      const RenderPlanSettings& plan) {
    const std::optional<SplatPlanKind> kind = SplatPlanKindOf(method);
    if (!kind) {
        return absl::InvalidArgumentError(absl::StrCat(
            "method \"", std::string(method), "\" is not a splatting method (light, bdpt, ppm)"));
    }
    if (plan.width <= 0 || plan.height <= 0) {
        return absl::InvalidArgumentError(
            absl::StrCat("image size ", plan.width, "x", plan.height, " is empty"));
    }
    if (plan.spp < 1 || plan.spp > kMaxSpp) {
        return absl::InvalidArgumentError(
            absl::StrCat("spp ", plan.spp, ": expected 1 to ", kMaxSpp));
    }
    if (plan.passes < 1) {
        return absl::InvalidArgumentError(absl::StrCat("passes ", plan.passes, " is below 1"));
    }
    SplatPlanSettings s;
    s.width = plan.width;
    s.height = plan.height;
    s.kind = *kind;
    s.spp = plan.spp;
    s.tile = plan.tile;
    s.passes = plan.passes;
    switch (*kind) {
        case SplatPlanKind::kLightPaths: {
            // Below 2^31 pixels x 2^24 spp: no overflow.
            s.light_paths = plan.spp * uint64_t(plan.width) * uint64_t(plan.height);
            const uint64_t passes = uint64_t(plan.passes);
            s.max_paths_per_task = std::min(kMaxLightPathsPerTask,
                                            s.light_paths / passes + (s.light_paths % passes != 0));
            break;
        }
        case SplatPlanKind::kCameraAndLight:
            break;
        case SplatPlanKind::kPhotonPasses: {
            const uint64_t passes = uint64_t(plan.passes);
            s.max_paths_per_task = plan.spp / passes + (plan.spp % passes != 0);
            s.tile = std::max(plan.tile, std::min(kPpmMaxTile, std::max(plan.width, plan.height)));
            break;
        }
    }
    return s;
}

}  // namespace lf
