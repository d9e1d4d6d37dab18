// `lightfarm plan`: what a render of a scene will model and what it will cost, before it runs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <set>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "lf/client/adaptive_flags.h"
#include "lf/client/command.h"
#include "lf/client/method_flags.h"
#include "lf/client/photon_flags.h"
#include "lf/client/radiosity_flags.h"
#include "lf/client/sample_flags.h"
#include "lf/client/scene_flags.h"
#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/core/medium.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/plural.h"
#include "lf/core/scene_loader.h"
#include "lf/job/job_spec.h"
#include "lf/job/method_registry.h"
#include "lf/job/plan.h"
#include "lf/job/settings.h"
#include "lf/job/splat_settings.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/whitted.h"
#include "lf/local/local_executor.h"
#include "lf/local/method_choice.h"
#include "lf/local/method_factory.h"
#include "lf/local/method_render.h"
#include "lf/local/render_prediction.h"

namespace lf {

namespace {

struct PlanOptions {
    std::string scene_path;
    SceneOptions scene;
    std::string method = "auto";
    double target_error = 0.01;
    double noise_threshold = 0;  // render --noise-threshold: explained, not costed
    uint64_t pilot_spp = 8;
    // The render's own settings, which decide its passes: --spp (its first pass), --tile,
    // --seed and --max-spp.
    uint64_t first_spp = defaults::kSpp;
    int tile = defaults::kTile;
    uint64_t seed = defaults::kSeed;
    uint64_t max_spp = defaults::kAdaptiveMaxSpp;
    RadiositySettings radiosity;  // the render's radiosity flags: mesh, form, solver
    int max_depth = defaults::kMaxDepth;
    int threads = 0;
    // --sampler, --light-sampling and --clamp: the pilot's noise, and so the samples, are
    // those of the render's
    SamplerType sampler = defaults::kSampler;
    LightStrategy light_strategy = defaults::kLightStrategy;
    double clamp = 0;
    PhotonSettings ppm;  // the ppm pilot's --photons, --ppm-radius, --ppm-alpha
    bool compare_methods = true;
};

// What render --noise-threshold will do; its cost depends on each pixel's noise, which plan
// does not pilot per pixel.
void PrintNoiseThresholdPlan(const PlanOptions& o) {
    const double t = o.noise_threshold;
    const uint64_t first =
        std::min(o.max_spp, std::max<uint64_t>(2, o.first_spp + o.first_spp % 2));
    std::printf(
        "render --noise-threshold %g samples per pixel as Cycles' Noise Threshold %g: every pixel "
        "takes --spp %llu samples (Cycles' automatic minimum for %g is %llu), then passes of 16 "
        "more (a quarter more from 64 on) while its error, sum |I - A| / (1e-4 + sqrt(sum I)) "
        "over R, G, B with I its mean and A its even samples' mean, is not below 5 x %g = %g, up "
        "to --max-spp %llu; the EXR's spp channel holds each pixel's count "
        "(docs/convergence.md)\n",
        t, t, (unsigned long long)first, t, (unsigned long long)NoiseThresholdMinSpp(t), t, 5 * t,
        (unsigned long long)o.max_spp);
}

std::string Color(const Rgb& c) { return absl::StrFormat("(%.3g, %.3g, %.3g)", c.r, c.g, c.b); }

// The fraction of light a surface reflects at normal incidence: a conductor's comes from its
// complex index of refraction (Fresnel), every other reflecting surface's from its reflectance.
Rgb NormalReflectance(const Material& m) {
    if (m.type != Material::Type::kGlossy || !m.conductor) return m.reflectance;
    auto f0 = [](float eta, float k) {
        return ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
    };
    return Rgb(f0(m.eta.r, m.k.r), f0(m.eta.g, m.k.g), f0(m.eta.b, m.k.b));
}

// Which of the material's parameters a texture drives.
std::string DescribeTextures(const Material& m) {
    std::string names;
    for (const auto& [ref, name] : {std::pair{&m.base_color_texture, "base colour"},
                                    {&m.metallic_roughness_texture, "metallic-roughness"},
                                    {&m.normal_texture, "normal"},
                                    {&m.emission_texture, "emission"}}) {
        if (ref->valid()) absl::StrAppend(&names, names.empty() ? ", textures: " : ", ", name);
    }
    return names;
}

// The parameters the material's model uses, and only those: a dielectric has an index of
// refraction, not a reflectance; a conductor has eta and k.
std::string DescribeSurface(const Material& m) {
    switch (m.type) {
        case Material::Type::kLambert:
        case Material::Type::kMirror:
            return "reflectance " + Color(m.reflectance) + DescribeTextures(m);
        case Material::Type::kPrincipled:
            return absl::StrFormat(
                       "base colour %s, metallic %.3g, roughness %.3g, specular %.3g, index of "
                       "refraction %.3g, transmission %.3g",
                       Color(m.reflectance), m.metallic, m.roughness, m.specular, m.ior,
                       m.transmission) +
                   DescribeTextures(m);
        case Material::Type::kGlossy:
            if (m.conductor) {
                return absl::StrFormat(
                    "conductor eta %s k %s (reflectance at normal incidence "
                    "%s), roughness %.3g",
                    Color(m.eta), Color(m.k), Color(NormalReflectance(m)), m.roughness);
            }
            return absl::StrFormat("specular tint (F0) %s, roughness %.3g", Color(m.reflectance),
                                   m.roughness);
        case Material::Type::kDielectric:
            return absl::StrFormat("index of refraction %.3g", m.ior);
        case Material::Type::kInterface:
            return "a boundary between media (neither reflects nor refracts)";
    }
    return "";
}

// A grid's lattice and what its dense copy holds in memory.
std::string DescribeGrid(const VolumeGrid& g) {
    return absl::StrFormat("%s %dx%dx%d (%.3g MiB)", g.name, g.size[0], g.size[1], g.size[2],
                           double(g.values.size() * sizeof(float)) / (1 << 20));
}

// A medium's coefficients, and its grids with their sizes.
std::string DescribeMedium(const Medium& m) {
    std::string out =
        absl::StrFormat("%s, sigma_a %s, sigma_s %s m^-1, g %.3g",
                        m.type == Medium::Type::kGrid ? "grid (at density 1)" : "homogeneous",
                        Color(m.sigma_a), Color(m.sigma_s), m.g);
    if (!m.emission.IsBlack()) absl::StrAppend(&out, ", emits ", Color(m.emission));
    for (const auto& [grid, what] : {std::pair{&m.density, "density"},
                                     {&m.emission_grid, "emission"},
                                     {&m.temperature, "temperature"}}) {
        if (*grid) absl::StrAppend(&out, ", ", what, " ", DescribeGrid(**grid));
    }
    return out;
}

// Radiosity's cost comes from pilot solves of 1/8 and 1/4 of the target's patches (about 1/4
// of the target's time together), at least 250: on coarser meshes the walls are a few patches,
// almost every pair touches, and the cost per pair is no longer the target's.
constexpr int64_t kRadiosityPilotDivisor = 8, kMinRadiosityPilotPatches = 250;

// Form-factor seconds for n unknowns as b n + a n^2 through the two pilots' times. Every pair
// of unknowns that see each other is computed and stored, the a n^2; but a pair closer than a
// few patch sizes takes up to 64 times the quadrature points and 16 times the rays of a far
// one, and each patch has a bounded number of such neighbours, the b n. On the Cornell box the
// near pairs are still half the time at 4000 patches, so one pilot scaled by n^2 predicted 10
// times the measured time. A fit that timing noise bends below 0 falls back to one term.
double PredictFormFactorSeconds(const RadiosityReport& small, const RadiosityReport& large,
                                double n) {
    const double n1 = double(small.sides), n2 = double(large.sides);
    const double per1 = small.form_factor_seconds / n1, per2 = large.form_factor_seconds / n2;
    const double a = (per2 - per1) / (n2 - n1), b = per1 - a * n1;
    if (a < 0) return per2 * n;
    if (b < 0) return per2 * n * n / n2;
    return b * n + a * n * n;
}

// A plan pilots radiosity on meshes of at most this many unknowns: a flat pilot's form factors
// are up to unknowns^2 floats (8000: 244 MiB), and a hierarchical one takes about a second per
// 10^4 unknowns.
constexpr int64_t kMaxFlatPilotSides = 8000, kMaxHierarchicalPilotSides = 50000;

// The solver's memory per unknown the hierarchical solve took on docs/radiosity.md's generated
// offices of 10^5 and 10^6 triangles (0.67 and 0.65 kB): what plan quotes for a scene too
// large to pilot.
constexpr double kHierarchicalBytesPerUnknown = 650;

// Flat: the solve's sweeps each read every stored form factor, and their number depends on the
// reflectances, not on the mesh, so the solve's time grows as n^2, like the form factors'
// memory. Hierarchical: links, tree and time grow about as n (links per unknown slowly, docs/
// radiosity.md), so the larger pilot is scaled linearly and its figures are a lower estimate.
absl::Status PrintRadiosityCost(const EmbreeScene& embree, const PlanOptions& options) {
    const RadiositySettings& target = options.radiosity;
    const bool hierarchical = target.form == "hierarchical";
    absl::StatusOr<PatchMesh> mesh =
        PatchMesh::Build(embree.scene(), {target.patch_size, target.patches});
    if (!mesh.ok()) return mesh.status();
    const double n = double(mesh->patches().size()), unknowns = double(mesh->sides().size());
    const std::string what = target.patch_size > 0
                                 ? absl::StrFormat("--patch-size %g", target.patch_size)
                                 : absl::StrFormat("--patches %lld", (long long)target.patches);
    std::printf(
        "radiosity (%s): %s -> %zu patches of size %.3g, %zu unknowns; %s\n", target.form.c_str(),
        what.c_str(), mesh->patches().size(), mesh->patch_size(), mesh->sides().size(),
        hierarchical ? absl::StrFormat("links grow about as the unknowns (link error %g, "
                                       "docs/radiosity.md)",
                                       target.link_error)
                           .c_str()
                     : absl::StrFormat("form factors grow as patches^2 (%.3g pairs at most, "
                                       "docs/radiosity.md)",
                                       n * n)
                           .c_str());
    if (const std::string drops = RadiosityDrops(embree.scene()); !drops.empty()) {
        std::printf("radiosity keeps the diffuse parts only; it drops %s\n", drops.c_str());
    }

    const int64_t patches = int64_t(mesh->patches().size());
    const int64_t small_patches =
        std::max(patches / kRadiosityPilotDivisor, kMinRadiosityPilotPatches);
    const int64_t max_pilot_sides = hierarchical ? kMaxHierarchicalPilotSides : kMaxFlatPilotSides;
    std::vector<RadiosityReport> pilots;
    for (int64_t pilot_patches : {small_patches, 2 * small_patches}) {
        RadiositySettings settings = target;
        settings.patch_size = 0;
        settings.patches = std::min(pilot_patches, patches);
        settings.max_patches = 0;
        // A scene of many triangles meshes no coarser than one patch each: the pilot can be
        // the target itself, and too large to run.
        absl::StatusOr<PatchMesh> pilot_mesh =
            PatchMesh::Build(embree.scene(), {0, settings.patches});
        if (!pilot_mesh.ok()) return pilot_mesh.status();
        if (int64_t(pilot_mesh->sides().size()) > max_pilot_sides) break;
        absl::StatusOr<RadiosityOptions> pilot_options = RadiosityOptionsOf(settings, 0);
        if (!pilot_options.ok()) return pilot_options.status();
        pilot_options->threads = options.threads;
        absl::StatusOr<std::unique_ptr<RadiosityRenderer>> pilot =
            PrepareRadiosity(embree, *pilot_options);
        if (!pilot.ok()) return pilot.status();
        pilots.push_back((*pilot)->report());
        const RadiosityReport& r = pilots.back();
        std::printf(
            "radiosity pilot: %lld patches, %lld unknowns: %s %.3f s (%.2f MiB), solve %.3f s "
            "(%s), estimated discretisation error %.3g (worst patch share %.3g)\n",
            (long long)r.patches, (long long)r.sides, hierarchical ? "links" : "form factors",
            r.form_factor_seconds,
            double(hierarchical ? r.solver_bytes : r.form_factor_bytes) / (1 << 20),
            r.solve_seconds, Plural(r.iterations, "iteration").c_str(), r.mean_estimated_error,
            r.estimated_error);
        if (r.sides >= int64_t(unknowns)) break;  // the target itself
    }
    const std::string render =
        absl::StrCat("render --method radiosity --radiosity ", target.form, " ", what);
    if (pilots.empty()) {
        const double bytes =
            hierarchical ? kHierarchicalBytesPerUnknown * unknowns : 4 * unknowns * unknowns;
        std::printf(
            "no radiosity pilot: the scene's triangles mesh to more than %lld unknowns even "
            "at the pilot's patch count; %s needs about %.0f MiB of %s%s\n",
            (long long)max_pilot_sides, render.c_str(), bytes / (1 << 20),
            hierarchical ? "links and cluster tree (docs/radiosity.md's offices)"
                         : "form factors (unknowns^2 floats at most)",
            hierarchical ? "" : "; --radiosity hierarchical grows about linearly instead");
        return absl::OkStatus();
    }
    const RadiosityReport& large = pilots.back();
    const double scale = unknowns / double(large.sides);
    double link_seconds, solve_seconds, bytes;
    if (hierarchical) {
        link_seconds = large.form_factor_seconds * scale;
        solve_seconds = large.solve_seconds * scale;
        bytes = double(large.solver_bytes) * scale;
    } else {
        // One pilot: the target itself (scale 1), or the second was too large to run.
        link_seconds = pilots.size() == 1 ? large.form_factor_seconds * scale * scale
                                          : PredictFormFactorSeconds(pilots[0], large, unknowns);
        solve_seconds = large.solve_seconds * scale * scale;
        bytes = double(large.form_factor_bytes) * scale * scale;
    }
    std::printf(
        "cost of %s: about %.1f s of %s (%.0f MiB) and %.1f s of solve at this speed, %.1f s "
        "before the display pass\n",
        render.c_str(), link_seconds, hierarchical ? "links" : "form factors", bytes / (1 << 20),
        solve_seconds, link_seconds + solve_seconds);
    // No prediction of the refined patch count: the worst share sits at discontinuities (a box
    // on the floor), which a finer uniform mesh does not improve and only refinement splits.
    std::printf(
        "with --target-error %.3g, radiosity refines the patches whose share of the estimated "
        "error (the pilots' worst above) is above it, up to --max-patches (default 16x "
        "--patches, at most %lld); docs/radiosity.md\n",
        options.target_error, (long long)kMaxRefinedPatches);
    return absl::OkStatus();
}

double TriangleArea(const TriangleMesh& mesh, const std::array<uint32_t, 3>& t) {
    const Vec3d a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    return 0.5 * Length(Cross(b - a, c - a));
}

// The Monte Carlo methods that render this scene completely, each costed for the target from
// a two-stage pilot over the whole image (RenderWithMethod, PredictMethodCost), fastest first
// named. Light tracing only where it sees everything (no mirror, glass or sky to look at);
// Whitted only where it is exact.
absl::Status PrintMethodCosts(const Scene& scene, const EmbreeScene& embree, const Camera& camera,
                              const PlanOptions& options, Method chosen) {
    const SceneTransport transport = AnalyzeTransport(scene);
    std::vector<Method> methods = {Method::kPath, Method::kBdpt, Method::kPpm};
    if (transport.specular.empty() && !scene.environment) methods.push_back(Method::kLight);
    if (transport.whitted_missing.empty()) methods.push_back(Method::kWhitted);
    // Media a method does not render, say: it would be costed for another image.
    std::erase_if(methods, [&](Method m) { return !CheckMethodTakesScene(m, scene).ok(); });
    const uint64_t stages[2] = {options.pilot_spp, 4 * options.pilot_spp};
    std::printf(
        "methods for --target-error %.4g: pilots of %llu then %llu spp over the whole image; "
        "error = sqrt of the A/B relMSE estimate (ppm's bias is not in it: its noise falls as "
        "passes^-alpha/2, the rate used)\n",
        options.target_error, (unsigned long long)stages[0], (unsigned long long)stages[1]);
    std::printf("  %-8s %9s %10s %6s %14s %14s\n", "method", "pilot s", "error", "rate",
                "spp to target", "s to target");
    MethodRenderSettings settings;
    settings.max_depth = options.max_depth;
    settings.seed = options.seed;
    settings.sampler = options.sampler;
    settings.light_strategy = options.light_strategy;
    settings.clamp = options.clamp;
    settings.threads = options.threads;
    settings.tile = options.tile;
    settings.ppm = options.ppm;
    std::optional<Method> fastest;
    double fastest_seconds = std::numeric_limits<double>::infinity(), path_seconds = 0;
    for (const Method method : methods) {
        MethodPilotStage measured[2];
        for (int k = 0; k < 2; ++k) {
            absl::StatusOr<RenderOutput> out =
                RenderWithMethod(method, embree, camera, settings, stages[k]);
            if (!out.ok()) return out.status();
            absl::StatusOr<double> relmse = EstimatedRelMse(out->image);
            if (!relmse.ok()) return relmse.status();
            measured[k] = {stages[k], out->seconds, std::sqrt(*relmse)};
        }
        const double ppm_rate = options.ppm.alpha / 2;
        absl::StatusOr<MethodCost> cost =
            method == Method::kPpm
                ? PredictMethodCost(measured[0], measured[1], options.target_error, ppm_rate,
                                    ppm_rate)
                : PredictMethodCost(measured[0], measured[1], options.target_error,
                                    kMinConvergenceRate, kMaxConvergenceRate);
        if (!cost.ok()) return cost.status();
        // The path tracer converges to an image without the caustics of delta lights: costed, but
        // not a candidate.
        const bool incomplete = method == Method::kPath && transport.delta_caustics();
        std::printf("  %-8s %9.2f %10.4g %6.2f %14.0f %14.1f%s\n",
                    std::string(MethodName(method)).c_str(),
                    measured[0].seconds + measured[1].seconds, measured[1].error, cost->rate,
                    cost->spp, cost->seconds,
                    incomplete ? absl::StrCat("  (incomplete: no caustics of the ",
                                              absl::StrJoin(transport.delta_lights, ", "), ")")
                                     .c_str()
                               : "");
        if (method == Method::kPath) path_seconds = cost->seconds;
        if (!incomplete && cost->seconds < fastest_seconds) {
            fastest_seconds = cost->seconds;
            fastest = method;
        }
    }
    std::printf("fastest to the target by its pilot: %s",
                fastest ? std::string(MethodName(*fastest)).c_str() : "");
    if (fastest != Method::kPath && fastest_seconds > 0 && !transport.delta_caustics()) {
        std::printf(" (%.1fx faster than path)", path_seconds / fastest_seconds);
    }
    std::printf(
        "%s\n",
        fastest == chosen
            ? ", the method chosen"
            : absl::StrCat("; the method chosen is ", MethodName(chosen), " (--method)").c_str());
    if (transport.caustics()) {
        std::printf(
            "  caustics here: a short pilot of path tracing sees little of them, so its error "
            "and cost are underestimated most\n");
    }
    return absl::OkStatus();
}

absl::Status RunPlan(const PlanOptions& options) {
    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    std::printf("scene %s: %dx%d, %zu meshes, %zu spheres, %zu point lights\n",
                options.scene_path.c_str(), scene->camera.width, scene->camera.height,
                scene->meshes.size(), scene->spheres.size(), scene->point_lights.size());

    std::set<int> used;
    for (const TriangleMesh& m : scene->meshes) used.insert(m.material);
    for (const Sphere& s : scene->spheres) used.insert(s.material);
    std::printf("materials in use:\n");
    float max_reflectance = 0;
    bool dielectric = false;
    for (int i : used) {
        const Material& m = scene->materials[size_t(i)];
        std::printf("  %s: %s, %s", m.name.c_str(), MaterialTypeName(m.type),
                    DescribeSurface(m).c_str());
        if (m.IsEmissive()) std::printf(", emits %s W m^-2 sr^-1", Color(m.emission).c_str());
        std::printf("\n");
        if (m.type == Material::Type::kDielectric) {
            dielectric = true;
        } else {
            max_reflectance = std::max(max_reflectance, NormalReflectance(m).MaxComponent());
        }
    }

    // An emission texture with no lit texel (glTF files give every material emissiveFactor 1
    // and a black texture) emits nothing.
    const auto emits = [&](const Material& m) {
        if (!m.IsEmissive() || !m.emission_texture.valid()) return m.IsEmissive();
        const TextureImage& t = *scene->textures[size_t(m.emission_texture.image)];
        const int colour = std::min(t.channels, 3) == 3 ? 3 : 1;
        for (size_t i = 0; i < size_t(t.width) * size_t(t.height); ++i) {
            for (int c = 0; c < colour; ++c) {
                const size_t k = i * size_t(t.channels) + size_t(c);
                if (t.texels8.empty() ? t.texels32[k] > 0 : t.texels8[k] > 0) return true;
            }
        }
        return false;
    };
    int emissive_triangles = 0, emissive_spheres = 0;
    double emitting_area = 0;
    for (const TriangleMesh& m : scene->meshes) {
        if (!emits(scene->materials[size_t(m.material)])) continue;
        for (const auto& t : m.triangles) {
            ++emissive_triangles;
            emitting_area += TriangleArea(m, t);
        }
    }
    for (const Sphere& s : scene->spheres) {
        if (emits(scene->materials[size_t(s.material)])) ++emissive_spheres;
    }
    const std::optional<EnvironmentLight>& sky = scene->environment;
    const std::string environment =
        !sky       ? "no environment"
        : sky->map ? absl::StrCat("an environment map (", sky->map->name, ")")
                   : absl::StrCat("a uniform environment ", Color(sky->radiance));
    std::printf(
        "lights: %d emissive triangles (%.4g m^2), %d emissive spheres, %zu point lights, %zu "
        "spot lights, %zu directional lights, %s\n",
        emissive_triangles, emitting_area, emissive_spheres, scene->point_lights.size(),
        scene->spot_lights.size(), scene->directional_lights.size(), environment.c_str());

    if (!scene->media.empty()) {
        std::printf("media:\n");
        for (const Medium& m : scene->media) {
            std::printf("  %s: %s\n", m.name.c_str(), DescribeMedium(m).c_str());
        }
        if (scene->camera_medium >= 0) {
            std::printf("the camera is in medium \"%s\"\n",
                        scene->media[size_t(scene->camera_medium)].name.c_str());
        }
    }

    const MethodChoice choice = ChooseMethod(*scene, MethodOfFlag(options.method));
    const Method method = choice.method;
    if (absl::Status s = CheckNoiseThresholdMethod(method, options.noise_threshold); !s.ok()) {
        return s;
    }
    // plan refuses what render and the farm refuse.
    if (absl::Status s = CheckMethodTakesScene(method, *scene); !s.ok()) return s;
    std::printf("method (--method %s): %s, because %s\n", options.method.c_str(),
                std::string(MethodName(method)).c_str(), choice.why.c_str());
    // What Whitted would give (lf/kernels/whitted.h), whether or not it is the method.
    if (absl::Status s = CheckMethodTakesScene(Method::kWhitted, *scene); !s.ok()) {
        std::printf("whitted: refuses this scene (%s)\n", std::string(s.message()).c_str());
    } else if (const std::vector<std::string> missing = WhittedMissingTerms(*scene);
               missing.empty()) {
        std::printf(
            "whitted: exact for this scene (direct light and specular chains are all its light "
            "transport): --method whitted converges to the path tracer's image at less cost\n");
    } else {
        std::printf("whitted: recommended only as a preview (--method whitted); it leaves out:\n");
        for (const std::string& term : missing) std::printf("  - %s\n", term.c_str());
    }

    if (method == Method::kWhitted) {
        // Splitting at each glass hit doubles the rays: the depth bounds the work.
        std::printf(
            "whitted depth: at most %d specular bounces%s; a ray tree splits in two at every "
            "dielectric hit and ends at the first non-specular one\n",
            options.max_depth < 0 ? kWhittedUnlimitedDepth : options.max_depth,
            options.max_depth < 0 ? " (its cap for an unlimited --max-depth)" : "");
    }
    // A closed room of albedo rho keeps a path alive for 1/(1 - rho) bounces on average under
    // the roulette; an open scene ends paths sooner.
    std::printf(
        "path depth: %s; Russian roulette from the second bounce (survival min(1, sqrt(max "
        "throughput channel))); largest reflectance %.3g, so paths average at most about "
        "%.1f bounces in a closed room of it\n",
        options.max_depth < 0 ? "unlimited"
                              : absl::StrFormat("at most %d bounces", options.max_depth).c_str(),
        max_reflectance, max_reflectance < 1 ? 1 / (1 - double(max_reflectance)) : INFINITY);
    if (dielectric) {
        std::printf(
            "  dielectrics pass on nearly all light, so paths inside glass last until "
            "they leave it\n");
    }

    PrepareSceneFor(method, *scene);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    if (Info(method).work == WorkKind::kRadiosity) {
        if (absl::Status s = PrintRadiosityCost(**embree, options); !s.ok()) return s;
    } else {
        std::printf("radiosity: not used\n");
    }

    const Camera camera(scene->camera, (*embree)->origin());
    // The splatting methods are not adaptive: the comparison of methods is their cost.
    if (Info(method).work == WorkKind::kSplatPasses) {
        return PrintMethodCosts(*scene, **embree, camera, options, method);
    }

    // The comparison of methods costs a target error, which a noise threshold is not.
    if (options.noise_threshold > 0) {
        PrintNoiseThresholdPlan(options);
        return absl::OkStatus();
    }
    // A pilot in two stages at the full resolution, each tile's error measured after both, so
    // that how fast it falls is measured rather than assumed (docs/convergence.md, "Error
    // estimates and plan predictions").
    // Radiosity's display error is costed with the path tracer's pilot, as before.
    const Method pilot_method = method == Method::kWhitted ? Method::kWhitted : Method::kPath;
    absl::StatusOr<std::unique_ptr<RadianceEstimator>> tracer =
        MakeRayTracer(pilot_method, **embree, options.max_depth, options.light_strategy);
    if (!tracer.ok()) return tracer.status();
    RenderSettings settings;
    settings.spp = options.first_spp;
    settings.seed = options.seed;
    settings.tile = options.tile;
    settings.threads = options.threads;
    settings.clamp = options.clamp;
    settings.sampler = options.sampler;
    const AdaptiveSettings adaptive{.target_error = options.target_error,
                                    .max_spp = options.max_spp};
    absl::StatusOr<RenderPrediction> p =
        PredictAdaptiveRender(camera, **tracer, settings, adaptive, options.pilot_spp);
    if (!p.ok()) return p.status();
    std::printf(
        "pilot (%s): %llu then %llu spp in every tile, %.2f s; the tiles' error goes "
        "as spp^%.2f (median over %d tiles; Monte Carlo's is spp^-0.5)\n",
        pilot_method == Method::kWhitted ? "whitted ray tracing" : "path tracing",
        (unsigned long long)p->pilot_spp[0], (unsigned long long)p->pilot_spp[1], p->pilot_seconds,
        -p->median_rate, p->tiles);
    std::printf(
        "cost of render --target-error %.4g --spp %llu: about %.0f spp on average (%.0f if "
        "every tile's error fell as spp^-1/2; %llu in the hardest tile, %d of %d tiles at "
        "--max-spp), %.1f s at this speed (%.1f); the pilot costs %.0f %% of that\n",
        options.target_error, (unsigned long long)options.first_spp, p->mean_spp, p->high_mean_spp,
        (unsigned long long)p->hardest_tile_spp, p->tiles_at_max_spp, p->tiles, p->seconds,
        p->high_seconds, 100 * p->pilot_seconds / std::max(p->seconds, 1e-9));
    if (p->tiles_disagreeing > 0) {
        std::printf(
            "warning: in %d of %d tiles the pilot's second stage has over 1.5x the error its first "
            "predicted (the first alone predicts %.0f spp): noise a short pilot does not see, "
            "such as caustics and fireflies; the prediction is less sure, a longer --pilot-spp "
            "makes it surer\n",
            p->tiles_disagreeing, p->tiles, p->first_stage_mean_spp);
    }
    return PrintMethodCosts(*scene, **embree, camera, options, method);
}

}  // namespace

Command AddPlanCommand(CLI::App& app) {
    auto options = std::make_shared<PlanOptions>();
    CLI::App* cmd = app.add_subcommand(
        "plan",
        "Say what a render of the scene will model and why: materials, lights and participating\n"
        "media (with their grids' sizes and memory) in use, the method --method picks, the path\n"
        "depth policy, for radiosity the patch count and the time and memory of the form\n"
        "factors or hierarchical links and the solve (from pilot solves of fewer patches; a\n"
        "mesh too large to pilot gets a memory bound instead), and the samples and time\n"
        "a target error needs (from a two-stage pilot render's own error estimates, how fast\n"
        "they fall, and its speed; give the render's --spp, --tile, --seed and --max-spp for\n"
        "its passes), then the same target's cost for\n"
        "each Monte Carlo method that renders the scene completely (path, bdpt, ppm; light\n"
        "where nothing specular or sky is seen; whitted where it is exact), each from a\n"
        "two-stage pilot of the whole image, and which is fastest.");
    cmd->add_option("scene", options->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    AddSceneFlags(cmd, options->scene);
    cmd->add_option("--method", options->method,
                    "the method to cost: path, radiosity (adds the cost of the form factors "
                    "and the solve, from a pilot solve), whitted (the pilot traces it), light, "
                    "bdpt, ppm, or auto (as render --method auto). Every Monte Carlo method that "
                    "renders the scene completely is costed as well, from its own pilot")
        ->capture_default_str()
        ->check([](const std::string& m) { return MethodFlagError(m, true); });
    cmd->add_option("--target-error", options->target_error,
                    "relative error to estimate the cost for")
        ->capture_default_str()
        ->check(CLI::Range(1e-6, 1.0));
    cmd->add_option("--noise-threshold", options->noise_threshold,
                    "explain render --noise-threshold (per-pixel, Cycles' rule) instead of "
                    "costing a target error and comparing methods; give the render's --spp "
                    "(default: Cycles' automatic minimum) and --max-spp")
        ->check(CLI::Range(kMinNoiseThreshold, 1.0));
    cmd->add_option("--pilot-spp", options->pilot_spp,
                    "samples per pixel of the pilot's first stage; the second takes 4x")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(2), uint64_t(1) << 16));
    cmd->add_option("--spp", options->first_spp, "the render's --spp: its first pass")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), kMaxSpp));
    cmd->add_option("--tile", options->tile, "the render's --tile")
        ->capture_default_str()
        ->check(CLI::Range(1, 65536));
    cmd->add_option("--seed", options->seed, "the render's --seed")->capture_default_str();
    cmd->add_option("--max-spp", options->max_spp, "the render's --max-spp")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(2), kMaxSpp));
    cmd->add_option("--max-depth", options->max_depth, "most bounces; -1 = unlimited")
        ->capture_default_str()
        ->check(CLI::Range(-1, kMaxDepthLimit));
    cmd->add_option("--threads", options->threads, "threads of the pilots; 0 = all cores")
        ->capture_default_str()
        ->check(CLI::Range(0, 1024));
    AddSamplerFlag(cmd, options->sampler);
    AddLightSamplingFlag(cmd, options->light_strategy);
    AddClampFlag(cmd, options->clamp);
    AddPhotonFlags(cmd, options->ppm);
    AddRadiosityFlags(cmd, options->radiosity);
    return {cmd, [cmd, options] {
                if (options->noise_threshold > 0 && cmd->count("--target-error") > 0) {
                    return ReportError(absl::InvalidArgumentError(
                        "--noise-threshold (per pixel) and --target-error (per tile): pick one"));
                }
                ApplyNoiseThresholdMinSpp(*cmd, {.noise_threshold = options->noise_threshold},
                                          options->first_spp);
                const absl::Status status = RunPlan(*options);
                return status.ok() ? 0 : ReportError(status);
            }};
}

}  // namespace lf
