#include <cstdio>
#include <filesystem>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "adaptive_flags.h"
#include "command.h"
#include "lf/job/job_spec.h"
#include "local_render.h"
#include "radiosity_flags.h"
#include "scene_flags.h"

namespace lf {

int ReportError(const absl::Status& status) {
    std::fprintf(stderr, "lightfarm: error: %s\n", std::string(status.message()).c_str());
    return 1;
}

absl::Status CheckExrPath(const std::string& path) {
    const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
    if (ext == ".exr") return absl::OkStatus();
    return absl::InvalidArgumentError(
        absl::StrCat("-o ", path, ": the image is written as OpenEXR, so the name must end in .exr",
                     ext == ".png" ? " (--png writes a preview PNG beside it)" : ""));
}

Command AddRenderCommand(CLI::App& app) {
    auto options = std::make_shared<LocalRenderOptions>();
    auto no_progress = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Render a scene in this process to an OpenEXR image, by path tracing or radiosity,\n"
        "through the same planner and merger as the farm.\n"
        "The EXR holds float32 R,G,B (mean radiance per pixel, W m^-2 sr^-1, box filter), the\n"
        "two half-sample estimates A.R,A.G,A.B and B.R,B.G,B.B (even and odd samples; their\n"
        "difference estimates the error) and spp, with header attributes lightfarm.* saying\n"
        "how the image was made. Same seed and settings give the same bits for any --tile and\n"
        "--threads.");
    cmd->add_option("scene", options->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    AddSceneFlags(cmd, options->scene);
    cmd->add_option("-o,--output", options->exr_path, "output OpenEXR file")->required();
    cmd->add_option("--png", options->png_path, "also write an sRGB PNG preview (clamped)");
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
    AddAdaptiveFlags(cmd, options->adaptive);
    cmd->add_flag("--no-progress", *no_progress, "no progress bar");
    cmd->add_option("--method", options->method,
                    "path (path tracing, any material), radiosity (finite elements, Lambertian "
                    "quads and triangles only, view-independent) or auto (radiosity when every "
                    "material is Lambertian and there are no spheres; the log says why)")
        ->capture_default_str()
        ->check(CLI::IsMember({"path", "radiosity", "auto"}));

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
        cmd, [cmd, options, no_progress] {
            options->progress = !*no_progress;
            if (absl::Status s = CheckExrPath(options->exr_path); !s.ok()) {
                return ReportError(s);
            }
            if (absl::Status s = CheckRadiosityFlagsApply(*cmd, options->method); !s.ok()) {
                return ReportError(s);
            }
            absl::StatusOr<LocalRenderSummary> summary = RunLocalRender(*options);
            if (!summary.ok()) return ReportError(summary.status());
            const double s = summary->render_seconds;
            std::printf(
                "job %s: %s, %dx%d, %llu samples in %.2f s: %.3f M samples/s, %.3f M rays/s, "
                "%llu NaN/Inf samples -> %s\n",
                summary->job_id.c_str(), summary->method.c_str(), summary->width, summary->height,
                (unsigned long long)summary->stats.samples, s, summary->stats.samples / s * 1e-6,
                summary->stats.rays / s * 1e-6, (unsigned long long)summary->stats.invalid_samples,
                options->exr_path.c_str());
            std::printf("time: load %.2f s, ", summary->load_seconds);
            if (const std::optional<RadiosityFigures>& r = summary->radiosity) {
                std::printf("radiosity %.2f s (mesh %.2f s, form factors %.2f s, solve %.2f s), ",
                            summary->radiosity_seconds, summary->mesh_seconds,
                            r->form_factor_seconds, r->solve_seconds);
            }
            std::printf("render %.2f s, total %.2f s\n", summary->render_seconds, summary->seconds);
            if (summary->estimated_error >= 0) {
                std::printf("estimated relative error %.4f%s\n", summary->estimated_error,
                            summary->high_variance ? " (high variance)" : "");
            }
            if (summary->adaptive) {
                const AdaptiveReport& a = summary->adaptive_report;
                std::printf(
                    "adaptive: %llu..%llu spp per pixel, worst tile %.4f, %d of %d tiles "
                    "above the target%s\n",
                    (unsigned long long)a.min_spp, (unsigned long long)a.max_spp,
                    a.worst_tile_error, a.tiles_above_target, a.tiles,
                    a.timed_out ? ", time limit reached" : "");
            }
            return 0;
        }};
}

}  // namespace lf
