#include "lf/client/bench.h"
#include "lf/client/command.h"
#include "lf/client/sample_flags.h"
#include "lf/client/scene_flags.h"

namespace lf {

Command AddBenchCommand(CLI::App& app) {
    auto options = std::make_shared<BenchOptions>();
    CLI::App* cmd = app.add_subcommand(
        "bench",
        "Measure path samples/s and rays/s on a scene, and Embree's raw closest-hit rate for\n"
        "incoherent rays in the same scene (the hardware limit for comparison).");
    cmd->add_option("scene", options->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--spp", options->spp, "samples per pixel")->capture_default_str();
    cmd->add_option("--threads", options->threads, "threads, at least 1")
        ->capture_default_str()
        ->check(CLI::Range(1, 1024));
    AddCameraFlag(cmd, options->scene);
    AddFilterFlag(cmd, options->scene);
    AddResolutionFlag(cmd, options->scene, "image size WxH, or N for N x N (default 256 x 256)");
    cmd->add_option("--max-depth", options->max_depth, "most bounces; -1 = unlimited")
        ->capture_default_str();
    AddSamplerFlag(cmd, options->sampler);
    AddLightSamplingFlag(cmd, options->light_strategy);
    cmd->add_option("--rays", options->raw_rays, "rays for the raw Embree measurement")
        ->capture_default_str();
    return {cmd, [options] {
                const absl::Status status = RunBench(*options);
                return status.ok() ? 0 : ReportError(status);
            }};
}

}  // namespace lf
