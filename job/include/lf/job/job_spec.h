// What a job asks for: the scene, as blobs, and every setting of its render. The same struct
// travels from the client (`submit`) through the coordinator to the workers, and local mode
// (`render`) fills it from the same flags, so both see the same defaults (settings.h).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "lf/core/scene_loader.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/method_registry.h"
#include "lf/job/plan.h"
#include "lf/job/scene_files.h"
#include "lf/job/settings.h"
#include "lf/job/shot.h"
#include "lf/job/splat_settings.h"

namespace lf {

// `submit --max-attempts` and `--blocklist-after`: their defaults, and the limit of both.
inline constexpr int kDefaultMaxAttempts = 3, kDefaultBlocklistAfter = 3;
inline constexpr int kMaxAttemptsLimit = 100;

struct JobSpec {
    std::string name;
    BlobRef scene;               // the scene JSON
    std::vector<BlobRef> files;  // the files it names
    // --camera and --resolution: the view of the scene this job renders (the loader checks them)
    SceneOptions scene_options;
    RenderPlanSettings plan;  // width and height come from the scene and scene_options
    uint64_t seed = defaults::kSeed;
    int max_depth = defaults::kMaxDepth;
    double clamp = 0;   // RenderSettings::clamp (lf/local/local_executor.h); 0: off
    uint32_t aovs = 0;  // lf/core/aov.h flags
    SamplerType sampler = defaults::kSampler;
    // The path tracer's; the job records and the EXR header name it (power or bvh).
    LightStrategy light_strategy = defaults::kLightStrategy;
    std::string method = defaults::kMethod;  // a name of lf/job/method_registry.h
    RadiositySettings radiosity;
    PhotonSettings ppm;         // method "ppm" (lf/job/splat_settings.h)
    AdaptiveSettings adaptive;  // IsAdaptive: plan.spp is the first pass, plan.passes unused
    ShotSettings shot;          // frames, fps, shutter, chunk (lf/job/shot.h); a still by default
    int priority = 0;           // higher first
    std::string scene_hash;     // the loader's content hash, for the EXR header
    std::string request_id;     // the client's, for idempotent retries; "" for none
    // The name of the token that submitted it (the server sets it, never the client); "" when
    // the server ran without authentication. A submitter token sees only its own jobs.
    std::string owner;
    // Leased only to workers having every one of these tags (lf/job/worker_tags.h); none: any.
    std::vector<std::string> tags;
    int max_workers = 0;  // distinct workers holding its leases at once; 0: no cap
    // Job management (issue 30): counted failures of one task that fail the job, and the
    // counted failures of one worker in this job after which it gets none of the job's tasks
    // (the blocklist, JobRecord::Blocklisted).
    int max_attempts = kDefaultMaxAttempts;
    int blocklist_after = kDefaultBlocklistAfter;
    // Dependencies (issue 30): job ids, each distinct; the job leases nothing until every one
    // has succeeded (lf/server/job_dependencies.h).
    std::vector<std::string> after;
};

// The limits of a job's settings, one list for the CLI's flags (`render`, `submit`) and the
// coordinator's check of a submission, so the wire refuses exactly what the CLI refuses. Spp and
// tile limits are kMaxSpp and kMaxFarmTile (plan.h); the patch budget kMaxRefinedPatches.
inline constexpr int kMaxDepthLimit = 1 << 20;  // max_depth in -1 (unlimited)..this
inline constexpr int kMaxPasses = 1 << 20;
// The tile limit of jobs with AOVs: a result then takes up to 236 bytes a pixel (tile_codec.h),
// and 128x128 of them (3.9 MB) stay under gRPC's 4 MiB message limit as kMaxFarmTile's 104
// bytes do.
inline constexpr int kMaxFarmAovTile = 128;
// Far beyond what an O(n^2) radiosity solve can handle; below the mesher's own hard limit.
inline constexpr int64_t kMaxPatchTarget = int64_t(1) << 24;
inline constexpr double kMinTolerance = 1e-12, kMaxTolerance = 1.0;
inline constexpr double kMinTargetError = 1e-6, kMaxTargetError = 1.0;  // or 0: none
inline constexpr double kMinNoiseThreshold = 1e-6;                      // or 0: none
inline constexpr double kMinTimeLimit = 1e-3, kMaxTimeLimit = 1e7;      // seconds, or 0: none
inline constexpr std::array<std::string_view, 3> kRadiositySolvers = {"jacobi", "gauss-seidel",
                                                                      "shooting"};
inline constexpr std::array<std::string_view, 2> kRadiosityDisplays = {"flat", "smooth"};
inline constexpr std::array<std::string_view, 2> kRadiosityForms = {"flat", "hierarchical"};
inline constexpr double kMinLinkError = 1e-9, kMaxLinkError = 1.0;

// Ok if every setting of `spec` is within the limits above (the scene and its files are checked
// where they are loaded); otherwise InvalidArgument naming the field and its allowed range, e.g.
// "radiosity.patches 1099511627776: expected 1 to 16777216".
absl::Status CheckJobSettings(const JobSpec& spec);

// Ok unless `r` names hierarchical radiosity with a solver other than jacobi: its gather is one
// pure step over the link hierarchy, so another solver named with it is a mistake, not a
// preference to ignore. Part of CheckJobSettings; local mode checks it on its own.
absl::Status CheckHierarchicalSolver(const RadiositySettings& r);

// Ok unless `noise_threshold` is set (> 0) for a method without per-pixel samples (only the
// tile methods have them): then InvalidArgument naming the method. `render`, `submit` and `plan`
// refuse alike.
absl::Status CheckNoiseThresholdMethod(Method method, double noise_threshold);

// Ok unless `shutter` opens (> 0) for a method that renders no motion blur
// (MethodInfo::motion_blur): then InvalidArgument naming the method.
absl::Status CheckShutterOfMethod(Method method, double shutter);

// The still that renders frame `frame` of `spec`'s shot: its frames are {frame, frame, 1}, one
// frame a task. Every frame of a shot renders as the still of that frame renders alone, locally
// or on the farm, so each gives the same bits.
JobSpec FrameSpec(const JobSpec& spec, int frame);

// Radiosity jobs the farm solves in patch-group tasks per sweep, rather than on every worker.
// Not adaptive ones: their passes are appended to the tasks where the sweeps would go.
inline bool SolvedInSweeps(const JobSpec& spec) {
    return FindMethod(spec.method) == Method::kRadiosity &&
           (spec.radiosity.solver == "jacobi" || spec.radiosity.form == "hierarchical") &&
           !IsAdaptive(spec.adaptive);
}

}  // namespace lf
