#include "lf/job/render_metadata.h"

#include <algorithm>
#include <limits>

#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"
#include "lf/core/pixel_filter.h"
#include "lf/job/method_registry.h"
#include "lf/version.h"

namespace lf {

namespace {

std::string YesNo(bool b) { return b ? "yes" : "no"; }

// Each channel the image has: the radiance with its error halves and sample counts, and the
// AOVs asked for.
std::string DescribeChannels(const RenderMetadata& m) {
    std::string text = absl::StrCat(
        "R,G,B: mean radiance W m^-2 sr^-1 (", DescribePixelFilter(m.filter),
        " filter); A.*, B.*: means of the even and odd samples; spp: samples per pixel");
    if (m.aovs & kAovAlbedo) absl::StrAppend(&text, "; albedo.R,G,B: first-hit albedo");
    if (m.aovs & kAovNormal) {
        absl::StrAppend(&text, "; normal.X,Y,Z: first-hit world-space shading normal");
    }
    if (m.aovs & kAovDepth) {
        absl::StrAppend(&text, "; depth.Z: first-hit distance from the camera along the ray");
    }
    if (m.aovs & kAovIlluminance) {
        absl::StrAppend(&text,
                        "; illuminance: illuminance on the first hit's side the camera sees, 683 "
                        "lm/W x Rec.709 luminance of the irradiance (0 for a miss)");
    }
    return text;
}

std::string DescribeUnits(const RenderMetadata& m) {
    return absl::StrCat("R,G,B: radiance W m^-2 sr^-1, linear Rec.709 RGB",
                        m.aovs & kAovDepth ? "; depth.Z: scene units" : "",
                        m.aovs & kAovIlluminance ? "; illuminance: lux (lm/m^2)" : "");
}

ExrAttributes DescribeMethod(const RenderMetadata& m) {
    return {
        {"lightfarm.version", std::string(kVersion)},
        {"lightfarm.sceneHash", m.scene_hash},
        {"lightfarm.method", m.method},
        {"lightfarm.spp", int(m.spp)},
        {"lightfarm.seed", std::to_string(m.seed)},
        {"lightfarm.maxDepth", m.max_depth},
        {"lightfarm.sampler", std::string(SamplerTypeName(m.sampler))},
        {"lightfarm.seconds", m.seconds},
        {"lightfarm.invalidSamples", std::to_string(m.stats.invalid_samples)},
        {"lightfarm.truncatedPaths", std::to_string(m.stats.truncated_paths)},
        {"lightfarm.rays", std::to_string(m.stats.rays)},
        {"lightfarm.channels", DescribeChannels(m)},
        {"lightfarm.filter", DescribePixelFilter(m.filter)},
        {"lightfarm.units", DescribeUnits(m)},
        // What a viewer needs to show the radiance in absolute terms: the primaries, and the
        // luminance in cd/m^2 of RGB (1, 1, 1), whose Y is 1 W m^-2 sr^-1, i.e. 683 cd/m^2.
        {"chromaticities", kRec709Chromaticities},
        {"whiteLuminance", 683.0f},
    };
}

// --clamp caps each sample, so the image is biased; the A/B estimates see only its variance.
void AddClampAttributes(double clamp, ExrAttributes& attributes) {
    attributes["lightfarm.clamp"] = clamp;
    attributes["lightfarm.bias"] = absl::StrCat(
        "clamp: each sample's radiance is scaled down so that no channel exceeds ", clamp,
        " W m^-2 sr^-1, so the image is biased (darker where bright paths were cut); "
        "lightfarm.estimatedError and the other error estimates measure the noise only, not "
        "this bias");
}

absl::StatusOr<ErrorEstimates> AddErrorEstimates(const Image& image, ExrAttributes& attributes) {
    ErrorEstimates e;
    absl::StatusOr<double> estimated = EstimatedRelativeError(image);
    if (!estimated.ok()) return estimated.status();
    absl::StatusOr<VarianceAssessment> variance = AssessVariance(image);
    if (!variance.ok()) return variance.status();
    e.estimated_error = *estimated;
    e.variance = *variance;
    attributes["lightfarm.estimatedError"] = e.estimated_error;
    attributes["lightfarm.estimatedRelMse"] = e.variance.relmse;
    attributes["lightfarm.estimatedMeanError"] = e.variance.mean_error;
    attributes["lightfarm.highVariance"] = YesNo(e.variance.high);
    return e;
}

void AddAdaptiveAttributes(const AdaptiveSettings& settings, const AdaptiveReport& report,
                           ExrAttributes& attributes) {
    attributes["lightfarm.targetError"] = settings.target_error;
    attributes["lightfarm.timeLimit"] = settings.time_limit;
    attributes["lightfarm.adaptive.worstTileError"] = report.worst_tile_error;
    attributes["lightfarm.adaptive.tilesAboveTarget"] = report.tiles_above_target;
    attributes["lightfarm.adaptive.timedOut"] = YesNo(report.timed_out);
    attributes["lightfarm.adaptive.minSpp"] = int(report.min_spp);
    attributes["lightfarm.adaptive.maxSpp"] = int(report.max_spp);
    if (settings.noise_threshold > 0) {
        attributes["lightfarm.noiseThreshold"] = settings.noise_threshold;
        // An int as minSpp; above 2^31 pixels, the most an int holds (images are smaller).
        attributes["lightfarm.adaptive.pixelsUnconverged"] =
            int(std::min<int64_t>(report.pixels_unconverged, std::numeric_limits<int>::max()));
    }
}

void AddRadiosityAttributes(const RenderMetadata& m, ExrAttributes& attributes) {
    const RadiositySettings& s = m.radiosity_settings;
    attributes["lightfarm.radiosity.solver"] = s.solver;
    attributes["lightfarm.radiosity.form"] = s.form;
    if (s.form == "hierarchical") {
        attributes["lightfarm.radiosity.linkError"] = s.link_error;
    }
    attributes["lightfarm.radiosity.tolerance"] = s.tolerance;
    attributes["lightfarm.radiosity.display"] = s.display;
    if (!m.radiosity) return;
    const RadiosityFigures& r = *m.radiosity;
    attributes["lightfarm.radiosity.patches"] = std::to_string(r.patches);
    attributes["lightfarm.radiosity.unknowns"] = std::to_string(r.unknowns);
    attributes["lightfarm.radiosity.patchSize"] = r.patch_size;
    attributes["lightfarm.radiosity.iterations"] = r.iterations;
    attributes["lightfarm.radiosity.residual"] = r.residual;
    attributes["lightfarm.radiosity.loaded"] = YesNo(r.loaded);
    attributes["lightfarm.radiosity.formFactorSeconds"] = r.form_factor_seconds;
    attributes["lightfarm.radiosity.solveSeconds"] = r.solve_seconds;
    attributes["lightfarm.radiosity.estimatedError"] = r.estimated_error;
    attributes["lightfarm.radiosity.meanEstimatedError"] = r.mean_estimated_error;
    // The one --target-error bounds both errors: the mesh's and the display's sampling.
    if (const double target = m.adaptive_settings.target_error; target > 0) {
        attributes["lightfarm.radiosity.targetError"] = target;
        attributes["lightfarm.radiosity.refinePasses"] = r.refine_passes;
        attributes["lightfarm.radiosity.coarsePatches"] = std::to_string(r.coarse_patches);
        attributes["lightfarm.radiosity.budgetReached"] = YesNo(r.budget_reached);
        attributes["lightfarm.radiosity.finestAboveTarget"] = std::to_string(r.finest_above_target);
    }
    if (r.links > 0) {
        attributes["lightfarm.radiosity.links"] = std::to_string(r.links);
        attributes["lightfarm.radiosity.linksPerSide"] = r.links_per_side;
        attributes["lightfarm.radiosity.linkBytes"] = std::to_string(r.link_bytes);
        attributes["lightfarm.radiosity.solverBytes"] = std::to_string(r.solver_bytes);
    }
}

// Light tracing traces spp light paths per pixel-equivalent; BDPT one light subpath per camera
// sample: the same count, spp x W x H.
void AddLightPathAttributes(const RenderMetadata& m, const Image& image,
                            ExrAttributes& attributes) {
    const uint64_t pixels = uint64_t(image.width()) * uint64_t(image.height());
    attributes["lightfarm.lightPaths"] = std::to_string(m.spp * pixels);
    attributes["lightfarm.lightPathsPerPixel"] = std::to_string(m.spp);
}

// Photon mapping is consistent, not unbiased: after N passes the kernel's radius leaves a bias
// that falls as N^(alpha - 1), and the A/B error estimates do not see it.
void AddPhotonAttributes(const RenderMetadata& m, ExrAttributes& attributes) {
    const PhotonSettings& p = m.ppm;
    attributes["lightfarm.ppm.passes"] = std::to_string(m.spp);
    attributes["lightfarm.ppm.photonsPerPass"] = std::to_string(p.photons_per_pass);
    attributes["lightfarm.ppm.initialRadius"] = p.initial_radius;
    attributes["lightfarm.ppm.alpha"] = p.alpha;
    attributes["lightfarm.ppm.radiusSchedule"] = absl::StrCat(
        "r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1), r_0 = ",
        p.initial_radius > 0 ? absl::StrCat(p.initial_radius, " scene units")
                             : std::string("the kernel's choice from the scene's size and frame"),
        ", alpha = ", p.alpha, " (Knaus and Zwicker 2011)");
    const std::string bias = absl::StrCat(
        "ppm: density estimation over the radius r_i of each pass blurs the light, so the image "
        "is biased; the bias falls as passes^(alpha - 1) = passes^",
        p.alpha - 1,
        " and lightfarm.estimatedError and the other error estimates measure the "
        "noise only, not this bias");
    auto [it, inserted] = attributes.try_emplace("lightfarm.bias", bias);
    if (!inserted) {
        std::get<std::string>(it->second) += "; " + bias;
    }
}

}  // namespace

absl::StatusOr<RenderDescription> DescribeRender(const RenderMetadata& m, const Image& image,
                                                 bool complete) {
    RenderDescription d;
    d.attributes = DescribeMethod(m);
    if (!m.camera.empty()) d.attributes["lightfarm.camera"] = m.camera;
    if (!m.sky.empty()) d.attributes["lightfarm.sky"] = m.sky;
    if (!m.partial.empty()) d.attributes["lightfarm.partial"] = m.partial;
    if (m.frame) {
        d.attributes["lightfarm.frame"] = *m.frame;
        d.attributes["lightfarm.time"] = FrameSeconds(*m.frame, m.fps);
        d.attributes["lightfarm.fps"] = m.fps;
        d.attributes["lightfarm.shutter"] = m.shutter;
    }
    if (m.aovs != 0) d.attributes["lightfarm.aovs"] = AovListName(m.aovs);
    const std::optional<Method> method = FindMethod(m.method);
    const MethodInfo* info = method ? &Info(*method) : nullptr;
    if (info && info->samples_lights) {
        d.attributes["lightfarm.lightSampling"] = std::string(LightStrategyName(m.light_strategy));
    }
    if (m.clamp > 0) AddClampAttributes(m.clamp, d.attributes);
    // An adaptive render's first pass gives every pixel at least 2 samples (it is even).
    const uint64_t fewest_spp = m.adaptive ? m.adaptive->min_spp : m.spp;
    if (complete && fewest_spp >= 2) {
        absl::StatusOr<ErrorEstimates> e = AddErrorEstimates(image, d.attributes);
        if (!e.ok()) return e.status();
        d.estimates = *e;
    }
    if (m.adaptive) AddAdaptiveAttributes(m.adaptive_settings, *m.adaptive, d.attributes);
    if (!info) return d;
    if (info->work == WorkKind::kRadiosity) AddRadiosityAttributes(m, d.attributes);
    if (info->splats_light_paths) AddLightPathAttributes(m, image, d.attributes);
    if (info->splat_plan == SplatPlanKind::kPhotonPasses) AddPhotonAttributes(m, d.attributes);
    return d;
}

RenderMetadata MetadataOf(const JobSpec& spec, const RenderOutcome& outcome) {
    RenderMetadata m;
    m.scene_hash = spec.scene_hash;
    m.camera = spec.scene_options.camera;
    m.sky = spec.scene_options.sky;
    m.method = spec.method;
    m.spp = outcome.adaptive ? outcome.adaptive->max_spp : spec.plan.spp;
    m.seed = spec.seed;
    m.max_depth = spec.max_depth;
    m.clamp = spec.clamp;
    m.aovs = spec.aovs;
    m.sampler = spec.sampler;
    m.light_strategy = spec.light_strategy;
    m.filter = spec.scene_options.filter.value_or(PixelFilter{});
    m.seconds = outcome.seconds;
    m.stats = outcome.stats;
    m.adaptive_settings = spec.adaptive;
    m.adaptive = outcome.adaptive;
    m.radiosity_settings = spec.radiosity;
    m.radiosity = outcome.radiosity;
    m.ppm = spec.ppm;
    m.partial = outcome.partial;
    // A shot's per-frame spec (FrameSpec) names one frame.
    if (spec.shot.frames && spec.shot.frames->count() == 1) {
        m.frame = spec.shot.frames->first;
        m.fps = spec.shot.fps;
        m.shutter = spec.shot.shutter;
    }
    return m;
}

}  // namespace lf
