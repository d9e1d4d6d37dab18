// The EXR header attributes that say how an image was made. `lightfarm render` and the farm's
// coordinator both build them with DescribeRender from the same inputs, so the two headers of
// one command line differ only in timings and host names.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/core/image_error.h"
#include "lf/core/image_io.h"
#include "lf/core/scene.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/job_spec.h"
#include "lf/job/plan.h"
#include "lf/job/settings.h"
#include "lf/job/splat_settings.h"

namespace lf {

// What a radiosity solve reports, in plain numbers: the farm carries them from the worker that
// solved to the coordinator that writes the header.
struct RadiosityFigures {
    int64_t patches = 0;
    int64_t unknowns = 0;
    double patch_size = 0;
    bool loaded = false;  // from a saved solution
    int iterations = 0;
    double residual = 0;
    double form_factor_seconds = 0, solve_seconds = 0;
    double estimated_error = 0, mean_estimated_error = 0;
    // With a target error: mesh refinement's passes, the first mesh's patches, and why it
    // stopped above the target if it did.
    int refine_passes = 0;
    int64_t coarse_patches = 0;
    bool budget_reached = false;
    int64_t finest_above_target = 0;
    // Hierarchical radiosity: links (between clusters and between sides), per side, their bytes
    // and all of the solver's; 0 for the flat method.
    int64_t links = 0;
    double links_per_side = 0;
    int64_t link_bytes = 0, solver_bytes = 0;
};

// The figures of a kernel's lf::RadiosityReport. A template so that the job model need not
// depend on the kernels; local mode and the worker both convert through it.
template <class Report>
RadiosityFigures RadiosityFiguresOf(const Report& r) {
    RadiosityFigures f;
    f.patches = r.patches;
    f.unknowns = r.sides;
    f.patch_size = r.patch_size;
    f.loaded = r.loaded;
    f.iterations = r.iterations;
    f.residual = r.residual;
    f.form_factor_seconds = r.form_factor_seconds;
    f.solve_seconds = r.solve_seconds;
    f.estimated_error = r.estimated_error;
    f.mean_estimated_error = r.mean_estimated_error;
    f.refine_passes = int(r.refinement.size());
    f.coarse_patches = r.refinement.empty() ? r.patches : r.refinement.front().patches;
    f.budget_reached = r.budget_reached;
    f.finest_above_target = r.finest_above_target;
    f.links = r.cluster_links + r.side_links;
    f.links_per_side = r.links_per_side;
    f.link_bytes = int64_t(r.link_bytes);
    f.solver_bytes = int64_t(r.solver_bytes);
    return f;
}

struct RenderMetadata {
    std::string scene_hash;
    std::string camera;  // the glTF camera --camera picked; "" for the scene's own
    std::string sky;     // --sky as given to the scene loader; "" for the scene's own
    std::string method;  // a name of lf/job/method_registry.h
    uint64_t spp = 0;    // adaptive: the most any pixel got
    uint64_t seed = 0;
    int max_depth = -1;
    double clamp = 0;    // 0: no clamping; otherwise the image is biased (lightfarm.clamp)
    uint32_t aovs = 0;   // lf/core/aov.h flags of the AOV channels the image has
    PixelFilter filter;  // the camera's, after --filter
    SamplerType sampler = defaults::kSampler;  // lightfarm.sampler
    // lightfarm.lightSampling, for the methods that sample lights at camera-path vertices (path,
    // whitted, bdpt, ppm; not radiosity nor light tracing)
    LightStrategy light_strategy = defaults::kLightStrategy;
    double seconds = 0;  // the whole render: loading, meshing, solving and sampling
    RenderStats stats;
    AdaptiveSettings adaptive_settings;
    std::optional<AdaptiveReport> adaptive;     // set for an adaptive render
    RadiositySettings radiosity_settings;       // method "radiosity"
    std::optional<RadiosityFigures> radiosity;  // when known
    PhotonSettings ppm;                         // method "ppm"
    std::string partial;  // lightfarm.partial: why and where the render stopped; "" complete
    // The frame of a shot (or `--frame N`): lightfarm.frame, .time, .fps, .shutter; nullopt
    // for a still.
    std::optional<int> frame;
    double fps = 0, shutter = 0;
};

// What a render of a job measured, for its header.
struct RenderOutcome {
    double seconds = 0;  // the whole render: loading, meshing, solving and sampling
    RenderStats stats;
    std::optional<AdaptiveReport> adaptive;  // set for an adaptive render
    std::optional<RadiosityFigures> radiosity;
    std::string partial;  // an interrupted render: what it holds (RenderMetadata::partial)
};

// The metadata of `spec` rendered with `outcome`, local mode's and the farm's alike (so their
// headers differ only in timings). spec.scene_options.filter is the filter the scene resolved to.
RenderMetadata MetadataOf(const JobSpec& spec, const RenderOutcome& outcome);

// What an image estimates of its own error, from its A/B halves: needs 2 samples per pixel.
struct ErrorEstimates {
    double estimated_error = 0;  // EstimatedRelativeError
    VarianceAssessment variance;
};

struct RenderDescription {
    ExrAttributes attributes;
    std::optional<ErrorEstimates> estimates;  // when computed
};

// Every attribute of a render's header: how it was made (lightfarm.version, scene hash, camera
// when picked by name, lightfarm.sky with --sky, lightfarm.partial for an interrupted render,
// method, settings with lightfarm.sampler and, for path tracing, lightfarm.lightSampling, timing,
// ray and sample counts, truncated paths), what the channels hold (lightfarm.channels,
// lightfarm.aovs when there are AOVs, lightfarm.filter), their units (lightfarm.units and OpenEXR's
// standard chromaticities, Rec.709 with D65, and whiteLuminance = 683 cd/m^2 for RGB (1, 1, 1)),
// the bias of --clamp (lightfarm.clamp and lightfarm.bias, only when clamping), the image's own
// error estimates (lightfarm.estimatedError, .estimatedRelMse, .estimatedMeanError, .highVariance:
// noise only, never the clamp's bias) when `complete` and every pixel has at least 2 samples, how
// an adaptive render ended (lightfarm.targetError, .timeLimit, lightfarm.adaptive.*), the radiosity
// solve (lightfarm.radiosity.*), the light paths of light tracing and BDPT (lightfarm.lightPaths,
// lightfarm.lightPathsPerPixel) and photon mapping's passes, photons and radius schedule with the
// bias it leaves (lightfarm.ppm.*, lightfarm.bias).
absl::StatusOr<RenderDescription> DescribeRender(const RenderMetadata& metadata, const Image& image,
                                                 bool complete);

}  // namespace lf
