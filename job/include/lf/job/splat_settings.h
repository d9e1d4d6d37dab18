// The job settings of the splatting methods (light tracing, BDPT, photon mapping: lf/job/splat_plan.h)
// and how a job's plain settings become their plan and their kernel's settings. Local mode
// (`lightfarm render`), the coordinator and the workers all map through here, so one command line
// gives one plan and one kernel configuration everywhere, hence the same bits.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/light_strategy.h"
#include "lf/core/sampler.h"
#include "lf/job/splat_plan.h"
#include "lf/job/plan.h"
#include "lf/job/settings.h"

namespace lf {

// `ppm`'s own settings (--photons, --ppm-radius, --ppm-alpha); the other methods ignore them.
struct PhotonSettings {
    uint64_t photons_per_pass = defaults::kPpmPhotonsPerPass;
    double initial_radius = defaults::kPpmInitialRadius;  // scene units; 0: the kernel's choice
    double alpha = defaults::kPpmAlpha;                   // in (0, 1)
};
// A pass's photon map is built whole in one task's memory (tens of bytes a photon): 2^28 photons
// are several GiB, far beyond any useful pass.
inline constexpr uint64_t kMaxPhotonsPerPass = uint64_t(1) << 28;

// Ok for settings within the limits above; InvalidArgument naming the field otherwise, e.g.
// "ppm.alpha 1: expected above 0 and below 1".
absl::Status CheckPhotonSettings(const PhotonSettings& ppm);

// The plan kind of a splatting method (MethodInfo::splat_plan); nullopt for the others and for
// unknown names.
std::optional<SplatPlanKind> SplatPlanKindOf(std::string_view method);
inline bool UsesSplatPlan(std::string_view method) { return SplatPlanKindOf(method).has_value(); }

// `ppm`'s tile: the whole frame up to this side. Each task of a tile rebuilds the photon maps of
// its passes (a pass's map is a pure function of the pass), so every extra tile repeats the
// photon tracing; whole-frame tiles trace each pass once. A 1024x1024 tile's camera sums are
// 104 MiB (TileSums, 104 bytes a pixel) in the worker and the merger.
inline constexpr int kPpmMaxTile = 1024;
// The most light paths a `light` task traces: its splat list then stays below 2^18 x (max depth
// + 1) entries before coalescing (64 bytes each in memory).
inline constexpr uint64_t kMaxLightPathsPerTask = kDefaultPathsPerTask;

// The largest task result a worker sends and the coordinator takes (CompleteTaskRequest), on
// both ends of the wire in place of gRPC's 4 MiB default: a splat task's result is its camera
// sums (104 bytes a pixel, at most kPpmMaxTile^2 pixels: 104 MiB) and its splat list (53 bytes
// an entry after coalescing, at most 2 entries a pixel of the frame: 879 MB on a 3840x2160
// frame whatever the task's paths or depth). So any task of a frame up to 4K, or of any frame
// whose light paths per task x (max depth + 1) x 53 bytes stay below it, fits; a worker whose
// result does not fails the task saying so (docs/farm.md, "Message sizes"). Below SQLite's
// default blob limit (10^9 bytes, SQLITE_MAX_LENGTH): the coordinator records each result as one
// blob, and a result it took but could not record would fail the job after the merge.
inline constexpr int kMaxTaskResultBytes = 960'000'000;

// The splat plan of `method` (a splatting method) for a render of plan.width x plan.height:
// - light: spp x W x H light paths (spp light paths per pixel-equivalent, so `--spp` means the
//   same effort per pixel as for the path tracer), in consecutive ranges of
//   min(kMaxLightPathsPerTask, ceil(N / plan.passes)) paths (`--passes` splits them as it splits
//   a tile's samples); splats grouped by plan.tile.
// - bdpt: plan's tiles x sample passes, as the path tracer's.
// - ppm: spp photon passes (one camera sample per pixel each) in ranges of ceil(spp / passes) on
//   tiles of the whole frame up to kPpmMaxTile a side (or plan.tile if larger).
// InvalidArgument when `method` is not a splatting method or the sizes are out of range.
absl::StatusOr<SplatPlanSettings> SplatPlanSettingsOf(std::string_view method,
                                                      const RenderPlanSettings& plan);

// The kernel's settings (lf::SplatRenderSettings) of a job's values. A template so that the job
// model need not depend on the kernels; local mode and the worker both convert through it.
template <class Settings>
Settings SplatRenderSettingsOf(int max_depth, uint64_t seed, SamplerType sampler, double clamp,
                               LightStrategy light_strategy, const PhotonSettings& ppm) {
    Settings s;
    s.max_depth = max_depth;
    s.seed = seed;
    s.sampler = sampler;
    s.clamp = clamp;
    s.light_strategy = light_strategy;
    s.photons_per_pass = ppm.photons_per_pass;
    s.initial_radius = ppm.initial_radius;
    s.alpha = ppm.alpha;
    return s;
}

}  // namespace lf
