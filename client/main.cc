// lightfarm: the command-line client. Each subcommand parses its options and calls a library.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "bench.h"
#include "lf/version.h"
#include "local_render.h"

namespace {

int Fail(const absl::Status& status) {
    std::fprintf(stderr, "lightfarm: error: %s\n", std::string(status.message()).c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "lightfarm: physically based rendering of the rendering equation, on one machine or a "
        "farm.\nSee docs/scene-format.md for the scene format."};
    app.set_version_flag("--version", std::string(lf::kVersion));
    app.require_subcommand(1);
    std::string log_level = "info";
    app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
        ->capture_default_str();

    lf::LocalRenderOptions render;
    bool no_progress = false;
    CLI::App* render_cmd = app.add_subcommand(
        "render",
        "Render a scene in this process (path tracing) to an OpenEXR image.\n"
        "The EXR holds float32 R,G,B (mean radiance per pixel, W m^-2 sr^-1, box filter), the\n"
        "two half-sample estimates A.R,A.G,A.B and B.R,B.G,B.B (even and odd samples; their\n"
        "difference estimates the error) and spp, with header attributes lightfarm.* saying\n"
        "how the image was made. Same seed and settings give the same bits for any --tile and\n"
        "--threads.");
    render_cmd->add_option("scene", render.scene_path, "scene file (JSON)")
        ->required()
        ->check(CLI::ExistingFile);
    render_cmd->add_option("-o,--output", render.exr_path, "output OpenEXR file")->required();
    render_cmd->add_option("--png", render.png_path, "also write an sRGB PNG preview (clamped)");
    render_cmd->add_option("--spp", render.render.spp, "samples per pixel")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 24));
    render_cmd->add_option("--seed", render.render.seed, "random seed")->capture_default_str();
    render_cmd->add_option("--max-depth", render.max_depth,
                           "most bounces per path; -1 = unlimited (Russian roulette ends paths)")
        ->capture_default_str()
        ->check(CLI::Range(-1, 1 << 20));
    render_cmd->add_option("--threads", render.render.threads, "worker threads; 0 = all cores")
        ->capture_default_str()
        ->check(CLI::Range(0, 1024));
    render_cmd->add_option("--tile", render.render.tile, "tile side in pixels")
        ->capture_default_str()
        ->check(CLI::Range(1, 65536));
    render_cmd->add_flag("--no-progress", no_progress, "no progress bar");

    lf::BenchOptions bench;
    CLI::App* bench_cmd = app.add_subcommand(
        "bench",
        "Measure path samples/s and rays/s on a scene, and Embree's raw closest-hit rate for\n"
        "incoherent rays in the same scene (the hardware limit for comparison).");
    bench_cmd->add_option("scene", bench.scene_path, "scene file (JSON)")
        ->required()
        ->check(CLI::ExistingFile);
    bench_cmd->add_option("--spp", bench.spp, "samples per pixel")->capture_default_str();
    bench_cmd->add_option("--threads", bench.threads, "threads")->capture_default_str();
    bench_cmd->add_option("--resolution", bench.resolution, "square image side (0 = scene's)")
        ->capture_default_str();
    bench_cmd->add_option("--max-depth", bench.max_depth, "most bounces; -1 = unlimited")
        ->capture_default_str();
    bench_cmd->add_option("--rays", bench.raw_rays, "rays for the raw Embree measurement")
        ->capture_default_str();

    CLI11_PARSE(app, argc, argv);
    spdlog::set_level(spdlog::level::from_str(log_level));

    if (*render_cmd) {
        render.progress = !no_progress;
        absl::StatusOr<lf::LocalRenderSummary> summary = lf::RunLocalRender(render);
        if (!summary.ok()) return Fail(summary.status());
        const double s = summary->seconds;
        std::printf(
            "job %s: %dx%d, %llu samples in %.2f s: %.3f M samples/s, %.3f M rays/s, %llu NaN/Inf "
            "samples -> %s\n",
            summary->job_id.c_str(), summary->width, summary->height,
            (unsigned long long)summary->stats.samples, s, summary->stats.samples / s * 1e-6,
            summary->stats.rays / s * 1e-6, (unsigned long long)summary->stats.invalid_samples,
            render.exr_path.c_str());
        return 0;
    }
    if (*bench_cmd) {
        absl::Status status = lf::RunBench(bench);
        return status.ok() ? 0 : Fail(status);
    }
    return 0;
}
