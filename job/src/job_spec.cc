#include "lf/job/job_spec.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/pixel_filter.h"
#include "lf/job/worker_tags.h"

namespace lf {

namespace {

template <typename T>
absl::Status InRange(const char* field, T value, T lo, T hi) {
    if (value >= lo && value <= hi) return absl::OkStatus();  // false for NaN
    return absl::InvalidArgumentError(
        absl::StrCat(field, " ", value, ": expected ", lo, " to ", hi));
}

// 0 for none, or a value in [lo, hi].
absl::Status NoneOrInRange(const char* field, double value, double lo, double hi) {
    if (value == 0 || (value >= lo && value <= hi)) return absl::OkStatus();
    return absl::InvalidArgumentError(
        absl::StrCat(field, " ", value, ": expected 0 (none) or ", lo, " to ", hi));
}

template <size_t N>
absl::Status OneOf(const char* field, const std::string& value,
                   const std::array<std::string_view, N>& names) {
    if (std::find(names.begin(), names.end(), value) != names.end()) return absl::OkStatus();
    std::string expected;
    for (std::string_view name : names) {
        absl::StrAppend(&expected, expected.empty() ? "" : ", ", std::string(name));
    }
    return absl::InvalidArgumentError(
        absl::StrCat(field, " \"", value, "\": expected one of ", expected));
}

// The methods' own limits (MethodInfo): the splatting methods make no AOVs and sample no
// adaptive passes. Ok for an unknown method, which CheckJobSettings refuses first.
absl::Status CheckMethodSettings(const JobSpec& spec) {
    const std::optional<Method> method = FindMethod(spec.method);
    if (!method) return absl::OkStatus();
    if (spec.aovs != 0 && !Info(*method).aovs) {
        return absl::InvalidArgumentError(absl::StrCat(
            "aovs: method \"", spec.method, "\" makes no AOV channels; use method path"));
    }
    if ((spec.aovs & kAovIlluminance) && !Info(*method).illuminance) {
        return absl::InvalidArgumentError(
            absl::StrCat("aovs: method \"", spec.method,
                         "\" has no estimate of AOV illuminance; use method path or radiosity"));
    }
    if (IsAdaptive(spec.adaptive) && !Info(*method).adaptive) {
        return absl::InvalidArgumentError(absl::StrCat(
            "adaptive: method \"", spec.method,
            "\" has no adaptive sampling (no target error, noise threshold or time limit); set "
            "spp instead"));
    }
    if (absl::Status s = CheckNoiseThresholdMethod(*method, spec.adaptive.noise_threshold);
        !s.ok()) {
        return s;
    }
    return CheckShutterOfMethod(*method, spec.shot.shutter);
}

}  // namespace

absl::Status CheckHierarchicalSolver(const RadiositySettings& r) {
    if (r.form != "hierarchical" || r.solver == "jacobi") return absl::OkStatus();
    return absl::InvalidArgumentError(
        absl::StrCat("radiosity.solver ", r.solver,
                     ": hierarchical radiosity solves by Jacobi sweeps (the solvers gauss-seidel "
                     "and shooting take --radiosity flat)"));
}

absl::Status CheckNoiseThresholdMethod(Method method, double noise_threshold) {
    // Radiosity's target error refines its mesh; its display samples are no noise to stop on.
    if (noise_threshold > 0 && Info(method).work != WorkKind::kTiles) {
        return absl::InvalidArgumentError(
            absl::StrCat("adaptive.noise_threshold: method \"", Info(method).name,
                         "\" has no per-pixel samples to stop; use method path or whitted"));
    }
    return absl::OkStatus();
}

absl::Status CheckJobSettings(const JobSpec& spec) {
    const RadiositySettings& r = spec.radiosity;
    const absl::Status checks[] = {
        InRange("spp", spec.plan.spp, uint64_t(1), kMaxSpp),
        // With AOVs a result takes up to 236 bytes a pixel, so tiles are smaller.
        InRange(spec.aovs == 0 ? "tile" : "tile (with AOVs)", spec.plan.tile, 1,
                spec.aovs == 0 ? kMaxFarmTile : kMaxFarmAovTile),
        InRange("passes", spec.plan.passes, 1, kMaxPasses),
        InRange("max_depth", spec.max_depth, -1, kMaxDepthLimit),
        // Finite: an infinite cap is no cap, and the CLI's 0 says that.
        InRange("clamp", spec.clamp, 0.0, std::numeric_limits<double>::max()),
        InRange("aovs", spec.aovs, 0u, uint32_t(kKnownAovs)),
        ParseMethod(spec.method).status(),
        NoneOrInRange("adaptive.target_error", spec.adaptive.target_error, kMinTargetError,
                      kMaxTargetError),
        NoneOrInRange("adaptive.time_limit", spec.adaptive.time_limit, kMinTimeLimit,
                      kMaxTimeLimit),
        InRange("adaptive.max_spp", spec.adaptive.max_spp, uint64_t(2), kMaxSpp),
        NoneOrInRange("adaptive.noise_threshold", spec.adaptive.noise_threshold, kMinNoiseThreshold,
                      1.0),
        CheckAdaptiveSettings(spec.adaptive),
        InRange("radiosity.patches", r.patches, int64_t(1), kMaxPatchTarget),
        // Finite: an infinite size would mesh every triangle as one patch, which no flag can ask.
        InRange("radiosity.patch_size", r.patch_size, 0.0, std::numeric_limits<double>::max()),
        OneOf("radiosity.solver", r.solver, kRadiositySolvers),
        InRange("radiosity.tolerance", r.tolerance, kMinTolerance, kMaxTolerance),
        InRange("radiosity.max_iterations", r.max_iterations, 1, std::numeric_limits<int>::max()),
        OneOf("radiosity.display", r.display, kRadiosityDisplays),
        InRange("radiosity.sweep_tasks", r.sweep_tasks, 1, kMaxSweepTasks),
        InRange("radiosity.max_patches", r.max_patches, int64_t(0), kMaxRefinedPatches),
        OneOf("radiosity.form", r.form, kRadiosityForms),
        InRange("radiosity.link_error", r.link_error, kMinLinkError, kMaxLinkError),
        CheckHierarchicalSolver(r),
        CheckPhotonSettings(spec.ppm),
        CheckShotSettings(spec.shot),
        CheckMethodSettings(spec),
        CheckTags(spec.tags, "tags"),
        InRange("max_workers", spec.max_workers, 0, std::numeric_limits<int>::max()),
        InRange("max_attempts", spec.max_attempts, 1, kMaxAttemptsLimit),
        InRange("blocklist_after", spec.blocklist_after, 1, kMaxAttemptsLimit),
    };
    for (const absl::Status& s : checks) {
        if (!s.ok()) return s;
    }
    // The camera name appears in messages and logs, like a file name.
    if (!spec.scene_options.camera.empty()) {
        if (absl::Status s = CheckScenePath(spec.scene_options.camera); !s.ok()) {
            return absl::InvalidArgumentError(absl::StrCat("camera: ", s.message()));
        }
    }
    // Like the camera name, the sky's text (or its file's name) appears in messages and logs.
    if (!spec.scene_options.sky.empty()) {
        if (absl::Status s = CheckScenePath(spec.scene_options.sky); !s.ok()) {
            return absl::InvalidArgumentError(absl::StrCat("sky: ", s.message()));
        }
    }
    // A cast from the wire or a record could hold any value; SampleOptions takes only these.
    if (spec.sampler != SamplerType::kIndependent && spec.sampler != SamplerType::kSobol) {
        return absl::InvalidArgumentError(
            absl::StrCat("sampler ", int(spec.sampler), ": expected independent or sobol"));
    }
    if (spec.light_strategy != LightStrategy::kPower &&
        spec.light_strategy != LightStrategy::kBvh) {
        return absl::InvalidArgumentError(
            absl::StrCat("light_strategy ", int(spec.light_strategy), ": expected power or bvh"));
    }
    if (spec.scene_options.filter) {
        if (absl::Status s = CheckPixelFilter(*spec.scene_options.filter); !s.ok()) {
            return absl::InvalidArgumentError(absl::StrCat("filter ", s.message()));
        }
    }
    return absl::OkStatus();
}

absl::Status CheckShutterOfMethod(Method method, double shutter) {
    if (shutter <= 0 || Info(method).motion_blur) return absl::OkStatus();
    return absl::InvalidArgumentError(
        absl::StrCat("shutter: method \"", MethodName(method),
                     "\" solves one instant per frame and renders no motion blur; set shutter 0"));
}

JobSpec FrameSpec(const JobSpec& spec, int frame) {
    JobSpec still = spec;
    still.shot.frames = FrameRange{frame, frame, 1};
    still.shot.chunk = 1;
    return still;
}

}  // namespace lf
