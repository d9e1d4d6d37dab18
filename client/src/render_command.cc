#include <csignal>
#include <cstdio>
#include <optional>
#include <string>

#include "absl/strings/str_format.h"
#include "lf/client/adaptive_flags.h"
#include "lf/client/command.h"
#include "lf/client/frame_flags.h"
#include "lf/client/method_flags.h"
#include "lf/client/output_flags.h"
#include "lf/client/photon_flags.h"
#include "lf/client/progress_bar.h"
#include "lf/client/radiosity_flags.h"
#include "lf/client/sample_flags.h"
#include "lf/client/scene_flags.h"
#include "lf/core/plural.h"
#include "lf/job/job_spec.h"
#include "lf/local/local_render.h"

namespace lf {

int ReportError(const absl::Status& status) {
    std::fprintf(stderr, "lightfarm: error: %s\n", std::string(status.message()).c_str());
    return 1;
}

namespace {

// The bar starts with the sampling, as its elapsed time and estimate are the sampling's. A
// shot has one such bar a frame and, below each, the shot's own.
class BarProgress : public RenderProgress {
  public:
    void Start() override { bar_.emplace(label_); }
    void Update(size_t done, size_t total) override { bar_->Update(done, total); }
    void Finish() override { bar_->Finish(); }
    void StartFrame(int index, int count, int frame) override {
        if (!shot_) shot_.emplace("shot  ");
        label_ = absl::StrFormat("frame %d", frame);
    }
    void FinishFrame(int done, int count) override {
        shot_->Update(done, count);
        shot_->Finish();
    }

  private:
    std::string label_ = "render";
    std::optional<ProgressBar> bar_, shot_;
};

RenderInterrupt render_interrupt;

// The first Ctrl-C while sampling can stop with a partial image asks for it; a second one, or
// one at any other time, ends the process at once (the default action).
extern "C" void OnInterrupt(int) {
    std::signal(SIGINT, SIG_DFL);
    if (!render_interrupt.honoured.load()) {
        std::raise(SIGINT);
        return;
    }
    render_interrupt.requested = true;
}

// The shell's status for a process ended by SIGINT.
constexpr int kInterruptedStatus = 128 + SIGINT;

// `render --frames`/`--frame`: a line a frame, then the shot's rate.
int RunShot(const LocalRenderOptions& options, const ShotSettings& shot) {
    std::signal(SIGINT, OnInterrupt);
    absl::StatusOr<LocalShotSummary> summary = RunLocalShot(options, shot);
    std::signal(SIGINT, SIG_DFL);
    if (!summary.ok()) return ReportError(summary.status());
    double pose = 0, bvh = 0, render = 0;
    for (const LocalFrameSummary& f : summary->frames) {
        const LocalRenderSummary& r = f.render;
        // Radiosity solves with each BVH it builds.
        const std::string built = f.bvh_seconds == 0 ? "reused"
                                  : r.radiosity
                                      ? absl::StrFormat("%.1f ms, radiosity %.2f s",
                                                        1e3 * f.bvh_seconds, r.radiosity_seconds)
                                      : absl::StrFormat("%.1f ms", 1e3 * f.bvh_seconds);
        std::printf(
            "frame %d (%.4f s): pose %.3f ms, BVH %s, render %.2f s, %.3f M samples/s -> %s\n",
            f.frame, f.time, 1e3 * f.pose_seconds, built.c_str(), r.render_seconds,
            r.stats.samples / r.render_seconds * 1e-6,
            OutputNames({f.exr_path, f.png_path}).c_str());
        pose += f.pose_seconds;
        bvh += f.bvh_seconds;
        render += r.render_seconds;
    }
    const size_t n = summary->frames.size();
    std::printf(
        "job %s: %s in %.2f s: %.2f frames per minute; mean per frame: pose %.3f ms, BVH %.1f "
        "ms%s, render %.3f s\n",
        summary->job_id.c_str(), Plural(int64_t(n), "frame").c_str(), summary->seconds,
        60.0 * double(n) / summary->seconds, 1e3 * pose / double(n), 1e3 * bvh / double(n),
        summary->moves ? "" : " (nothing moves: built once)", render / double(n));
    if (!summary->partial.empty()) {
        std::fprintf(stderr, "lightfarm: %s\n", summary->partial.c_str());
        return kInterruptedStatus;
    }
    return 0;
}

}  // namespace

Command AddRenderCommand(CLI::App& app) {
    auto options = std::make_shared<LocalRenderOptions>();
    auto output = std::make_shared<OutputFlags>();
    auto no_progress = std::make_shared<bool>(false);
    auto method = std::make_shared<std::string>(defaults::kMethod);
    auto frame_flags = std::make_shared<FrameFlags>();
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Render a scene in this process to an OpenEXR image and/or a PNG preview, by path\n"
        "tracing, radiosity, Whitted ray tracing, light tracing, bidirectional path tracing or\n"
        "progressive photon mapping, through the same planner and merger as the farm.\n"
        "The EXR holds float32 R,G,B (mean radiance per pixel, W m^-2 sr^-1, linear Rec.709,\n"
        "through the pixel filter), the two half-sample estimates A.R,A.G,A.B and B.R,B.G,B.B\n"
        "(even and odd samples; their difference estimates the error), spp, and the --aov\n"
        "channels, with header attributes lightfarm.* saying how the image was made. Same seed\n"
        "and settings give the same bits for any --tile and --threads.\n"
        "Ctrl-C while path, whitted or radiosity's display sample stops them: the files get the\n"
        "whole passes done so far (each pixel the mean of its own samples, in spp), the header\n"
        "says lightfarm.partial, and the exit status is 130. A second Ctrl-C, or one during\n"
        "loading, solving or a splatting method, ends it at once.\n"
        "--frames A-B[:STEP] renders an animated scene's frames (glTF animations, skins and\n"
        "morph targets), frame f at f / --fps seconds, each to -o and --png with the frame number\n"
        "in place of their run of # (out_####.exr -> out_0012.exr); --frame N renders one. The\n"
        "scene loads once; the BVH and the method's kernel are built again only for frames where\n"
        "something moved (radiosity solves each such frame). Each frame is the still that frame\n"
        "gives alone (same seed, same bits), its header adds lightfarm.frame, .time, .fps and\n"
        ".shutter. Ctrl-C while a frame samples writes that frame partial and ends the shot\n"
        "(status 130).");
    cmd->add_option("scene", options->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    AddSceneFlags(cmd, options->scene);
    AddSkyFlag(cmd, options->scene);
    AddOutputFlags(cmd, *output);
    AddFrameFlags(cmd, *frame_flags);
    cmd->add_option("--spp", options->render.spp, "samples per pixel")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), kMaxSpp));
    cmd->add_option("--seed", options->render.seed, "random seed")->capture_default_str();
    cmd->add_option("--max-depth", options->max_depth,
                    "most bounces per path; -1 = unlimited (Russian roulette ends paths)")
        ->capture_default_str()
        ->check(CLI::Range(-1, kMaxDepthLimit));
    cmd->add_option("--threads", options->render.threads, "worker threads; 0 = all cores")
        ->capture_default_str()
        ->check(CLI::Range(0, 1024));
    cmd->add_option("--tile", options->render.tile, "tile side in pixels")
        ->capture_default_str()
        ->check(CLI::Range(1, 65536));
    cmd->add_option("--passes", options->render.passes,
                    "sample passes per tile, as a farm job would split them (same bits)")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxPasses));
    AddSampleFlags(cmd, options->render.sampler, options->render.light_strategy,
                   options->render.clamp, options->render.aovs);
    AddAdaptiveFlags(cmd, options->adaptive);
    cmd->add_flag("--no-progress", *no_progress, "no progress bar");
    cmd->add_option("--method", *method,
                    "path (path tracing, any material), radiosity (finite elements, Lambertian "
                    "quads and triangles only, view-independent), whitted (direct light and "
                    "mirror/glass reflection and refraction only: a fast preview without "
                    "interreflection or caustics), light (light tracing: --spp light paths per "
                    "pixel from the lights, each connected to the camera and splatted anywhere on "
                    "the image), bdpt (bidirectional path tracing: every connection of a camera "
                    "and a light subpath, weighted by MIS), ppm (progressive photon mapping: --spp "
                    "passes of --photons photons each, a shrinking gather radius; consistent, "
                    "biased at any finite pass count) or auto (path for scattering, emitting or "
                    "grid media, which only path and bdpt render; whitted where it is exact: no "
                    "interreflection nor caustics; else radiosity where it is exact: Lambertian "
                    "quads and triangles; else bdpt for caustics of small emitters through "
                    "specular surfaces; else path; the log says why). light, bdpt and ppm take no "
                    "--aov nor adaptive sampling")
        ->capture_default_str()
        ->check([](const std::string& m) { return MethodFlagError(m, true); });

    AddPhotonFlags(cmd, options->ppm);

    const std::string r = "Radiosity";
    AddRadiosityFlags(cmd, options->radiosity);
    cmd->add_option("--save-solution", options->save_solution,
                    "write the solved radiosity, to render other cameras without solving")
        ->group(r);
    cmd->add_option("--load-solution", options->load_solution,
                    "reuse a saved solution (must match the scene and mesh)")
        ->group(r)
        ->check(CLI::ExistingFile);
    cmd->add_option("--export-ply", options->export_ply,
                    "write the solution as a PLY mesh with per-vertex sRGB colours")
        ->group(r);

    return {
        cmd, [cmd, options, output, no_progress, method, frame_flags] {
            ApplyNoiseThresholdMinSpp(*cmd, options->adaptive, options->render.spp);
            absl::StatusOr<OutputPaths> paths = ResolveOutputPaths(*output);
            if (!paths.ok()) return ReportError(paths.status());
            absl::StatusOr<ShotSettings> shot = ShotOfFrameFlags(*frame_flags);
            if (!shot.ok()) return ReportError(shot.status());
            if (absl::Status s = ResolveSkyFile(options->scene_path, options->scene); !s.ok()) {
                return ReportError(s);
            }
            options->exr_path = paths->exr;
            options->png_path = paths->png;
            options->preview = output->preview;
            options->false_color = output->false_color;
            options->false_color_path = paths->false_color;
            if (absl::Status s = CheckRadiosityFlagsApply(*cmd, *method); !s.ok()) {
                return ReportError(s);
            }
            if (absl::Status s = CheckPhotonFlagsApply(*cmd, *method); !s.ok()) {
                return ReportError(s);
            }
            if (shot->frames) {
                if (absl::Status s = CheckShotOutputs(*options, *shot->frames); !s.ok()) {
                    return ReportError(s);
                }
            }
            for (const std::string* path :
                 {&options->exr_path, &options->png_path, &options->false_color_path}) {
                const std::string first =
                    shot->frames ? FramePath(*path, shot->frames->first) : *path;
                if (absl::Status s = CheckWritable(first); !s.ok()) return ReportError(s);
            }
            options->method = MethodOfFlag(*method);
            BarProgress bar;
            options->progress = *no_progress ? nullptr : &bar;
            options->interrupt = &render_interrupt;
            if (shot->frames) return RunShot(*options, *shot);
            std::signal(SIGINT, OnInterrupt);
            absl::StatusOr<LocalRenderSummary> summary = RunLocalRender(*options);
            std::signal(SIGINT, SIG_DFL);
            if (!summary.ok()) return ReportError(summary.status());
            const double s = summary->render_seconds;
            std::printf(
                "job %s: %s, %dx%d, %llu samples in %.2f s: %.3f M samples/s, %.3f M rays/s, "
                "%llu NaN/Inf samples -> %s\n",
                summary->job_id.c_str(), std::string(MethodName(summary->method)).c_str(),
                summary->width, summary->height, (unsigned long long)summary->stats.samples, s,
                summary->stats.samples / s * 1e-6, summary->stats.rays / s * 1e-6,
                (unsigned long long)summary->stats.invalid_samples, OutputNames(*paths).c_str());
            std::printf("time: load %.2f s, ", summary->load_seconds);
            if (const std::optional<RadiosityFigures>& r = summary->radiosity) {
                std::printf("radiosity %.2f s (mesh %.2f s, form factors %.2f s, solve %.2f s), ",
                            summary->radiosity_seconds, summary->mesh_seconds,
                            r->form_factor_seconds, r->solve_seconds);
            }
            std::printf("render %.2f s, total %.2f s\n", summary->render_seconds, summary->seconds);
            if (summary->estimated_error >= 0) {
                std::printf("estimated relative error of the whole image %.4f%s%s\n",
                            summary->estimated_error,
                            summary->high_variance ? " (high variance)" : "",
                            options->render.clamp > 0
                                ? " (noise only: --clamp biases the image, and this error does "
                                  "not include that bias)"
                                : "");
            } else if (options->render.clamp > 0) {
                std::printf("--clamp %g: the image is biased\n", options->render.clamp);
            }
            if (summary->adaptive) {
                const AdaptiveReport& a = summary->adaptive_report;
                // The target bounds each tile's error, not the whole image's above.
                const double target = options->adaptive.target_error;
                const double threshold = options->adaptive.noise_threshold;
                const std::string tiles =
                    threshold > 0
                        ? absl::StrFormat("--noise-threshold %g: %lld of %lld pixels not converged",
                                          threshold, (long long)a.pixels_unconverged,
                                          (long long)a.pixels)
                    : target > 0 ? absl::StrFormat(
                                       "--target-error %g bounds each tile's error: worst tile "
                                       "%.4f, %d of %s above it",
                                       target, a.worst_tile_error, a.tiles_above_target,
                                       Plural(a.tiles, "tile"))
                                 : absl::StrFormat("worst tile error %.4f", a.worst_tile_error);
                std::printf("adaptive: %llu..%llu spp per pixel (mean %.0f); %s%s\n",
                            (unsigned long long)a.min_spp, (unsigned long long)a.max_spp,
                            a.mean_spp, tiles.c_str(), a.timed_out ? ", time limit reached" : "");
            }
            if (!summary->partial.empty()) {
                std::fprintf(stderr, "lightfarm: %s; wrote it to %s\n", summary->partial.c_str(),
                             OutputNames(*paths).c_str());
                return kInterruptedStatus;
            }
            return 0;
        }};
}

}  // namespace lf
