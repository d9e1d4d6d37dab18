// Every render method in one table: its name (what JobSpec::method, the wire and the job store
// carry), the kind of work it is planned into and what it can and cannot do. Everything else
// asks the table (Info) instead of comparing names; lf/local/method_factory.h builds each
// method's kernel.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/scene.h"
#include "lf/job/splat_plan.h"

namespace lf {

struct JobSpec;

enum class Method { kPath, kRadiosity, kWhitted, kLight, kBdpt, kPpm };

enum class WorkKind {
    kTiles,        // samples of pixel tiles (lf/job/plan.h): path, whitted
    kSplatPasses,  // splat passes whose results splat or gather anywhere (lf/job/splat_plan.h)
    kRadiosity,    // a radiosity solve, then tiles of its display
};

struct MethodInfo {
    Method method;
    const char* name;
    WorkKind work;
    std::optional<SplatPlanKind> splat_plan;  // kSplatPasses only
    // A splat lands in the one pixel that holds its raster position: the box filter's footprint,
    // so these take the box filter only (CheckMethodTakesScene).
    bool splats_light_paths;
    // Samples lights at camera-path vertices (lightfarm.lightSampling names the strategy).
    bool samples_lights;
    // Splat passes have no per-pixel first hits to make AOVs of, and no tile whose error alone
    // decides its next pass.
    bool aovs;
    // Estimates the illuminance AOV (RadianceEstimator::Irradiance): the path tracer and
    // radiosity; whitted has no diffuse indirect light to estimate it with.
    bool illuminance;
    bool adaptive;  // --target-error, --time-limit
    // Renders a shutter interval (--shutter): radiosity solves one instant per frame.
    bool motion_blur;
    // Takes triangles only: PrepareSceneFor tessellates the spheres (radiosity's patches).
    bool meshes_spheres;
    // The scenes the method cannot represent: why, as a status; nullptr when it takes any.
    // Whitted's omissions (lf::WhittedMissingTerms) are logged, not refused.
    absl::Status (*scene_refusal)(const Scene& scene);
};

// Every method, in the order `--help` and error messages list them.
std::span<const MethodInfo> AllMethods();
const MethodInfo& Info(Method method);
const char* MethodName(Method method);

// The method named `name`; nullopt for any other name.
std::optional<Method> FindMethod(std::string_view name);
// InvalidArgument listing the methods for an unknown name: `method "photon": expected one of
// path, radiosity, whitted, light, bdpt, ppm`.
absl::StatusOr<Method> ParseMethod(std::string_view name);
// The method of a spec CheckJobSettings passed: an unknown name is a broken invariant (aborts).
Method MethodOf(const JobSpec& spec);

// Ok when `method` can render `scene` as its camera sees it: FailedPrecondition naming the
// method and the pixel filter for a splatting method and a filter other than the box, or for a
// splatting method and an orthographic camera; the method's scene_refusal otherwise.
absl::Status CheckMethodTakesScene(Method method, const Scene& scene);
// The scene as `method`'s kernels see it, made once after loading and before the BVH is built:
// every render of it (local, the farm's workers, plan, converge) calls this, so all build the
// same geometry and give the same bits. Radiosity: spheres become meshes (TessellateSpheres).
// The scene's content hash, which names the input, is kept.
void PrepareSceneFor(Method method, Scene& scene);
// What only the path tracer and bdpt render of the scene's participating media: "" when every
// medium is a homogeneous absorber (Beer's law: no scattering, no emission), no surface is an
// interface and the camera is in vacuum, else why not ("medium \"fog\" scatters light
// (sigma_s > 0)"). The scene_refusal of whitted, radiosity, light and ppm refuses such scenes.
std::string MediaLimitation(const Scene& scene);
// What of the media bdpt does not render: "" unless a medium emits ("medium \"fire\" emits
// light"; bdpt's subpaths neither hit nor sample emissive media). Its scene_refusal.
std::string BdptMediaLimitation(const Scene& scene);
// The pixel filter part of CheckMethodTakesScene, for a camera already built.
absl::Status CheckMethodTakesFilter(Method method, const PixelFilter& filter);

}  // namespace lf
