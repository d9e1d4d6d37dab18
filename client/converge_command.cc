#include <cstdio>

#include "command.h"
#include "convergence.h"
#include "lf/job/job_spec.h"
#include "sample_flags.h"
#include "scene_flags.h"

namespace lf {

Command AddConvergeCommand(CLI::App& app) {
    auto options = std::make_shared<ConvergenceOptions>();
    CLI::App* cmd = app.add_subcommand(
        "converge",
        "Measure error against time: render a ladder of budgets (path tracing: 1, 2, 4, ...\n"
        "spp; radiosity: doubling patch counts), compare each image with a reference and write\n"
        "DIR/convergence.csv (method,budget,seconds,rmse,relmse,smape,estimated_relmse) and "
        "DIR/convergence.png\n"
        "(log-log relative RMSE, sqrt(relmse), against seconds, fitted slope per method;\n"
        "drawn by gnuplot).\n"
        "Without --reference, a path-traced reference is rendered first (and the output says\n"
        "so). See docs/convergence.md.");
    cmd->add_option("scene", options->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out_dir, "output directory (created)")->required();
    cmd->add_option("--reference", options->reference_path,
                    "reference OpenEXR of the same size (R,G,B)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--method", options->method, "path, radiosity or both")
        ->capture_default_str()
        ->check(CLI::IsMember({"path", "radiosity", "both"}));
    AddCameraFlag(cmd, options->scene);
    AddFilterFlag(cmd, options->scene);
    AddResolutionFlag(cmd, options->scene, &options->resolution, 16384,
                      "image size WxH, or N for width N with the scene's aspect (0 = the scene's)");
    cmd->add_option("--max-spp", options->max_spp, "largest spp of the path ladder")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(2), uint64_t(1) << 20));
    cmd->add_option("--reference-spp", options->reference_spp,
                    "spp of the path-traced reference when none is given")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), kMaxSpp));
    cmd->add_option("--min-patches", options->min_patches, "smallest radiosity patch target")
        ->capture_default_str()
        ->check(CLI::Range(int64_t(1), kMaxPatchTarget));
    cmd->add_option("--max-patches", options->max_patches, "largest radiosity patch target")
        ->capture_default_str()
        ->check(CLI::Range(int64_t(1), kMaxPatchTarget));
    cmd->add_option("--tolerance", options->radiosity_tolerance,
                    "radiosity solver tolerance (relative residual)")
        ->capture_default_str()
        ->check(CLI::Range(kMinTolerance, kMaxTolerance));
    cmd->add_option("--radiosity-spp", options->radiosity_spp,
                    "camera rays per pixel through a radiosity solution")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 16));
    cmd->add_option("--seed", options->seed, "random seed (the own reference uses seed + 1)")
        ->capture_default_str();
    cmd->add_option("--threads", options->threads, "worker threads; 0 = all cores")
        ->capture_default_str()
        ->check(CLI::Range(0, 1024));
    cmd->add_option("--max-depth", options->max_depth, "most bounces; -1 = unlimited")
        ->capture_default_str()
        ->check(CLI::Range(-1, kMaxDepthLimit));
    AddSamplerFlag(cmd, options->sampler);
    return {cmd, [options] {
                absl::StatusOr<ConvergenceResult> result = RunConvergence(*options);
                if (!result.ok()) return ReportError(result.status());
                std::printf("%s", result->reference.c_str());
                if (result->reference_rmse > 0) {
                    std::printf(" (its own RMSE estimate from A/B: %.3e)", result->reference_rmse);
                }
                std::printf("\nmethod,budget,seconds,rmse,relmse,smape,estimated_relmse\n");
                for (const ConvergenceRow& row : result->rows) {
                    std::printf("%s,%lld,%.4f,%.4e,%.4e,%.4e,%s\n", row.method.c_str(),
                                (long long)row.budget, row.seconds, row.error.rmse,
                                row.error.relmse, row.error.smape,
                                EstimatedRelMseField(row).c_str());
                }
                for (const auto& [method, slope] : result->slopes) {
                    std::printf("%s: sqrt(relmse) ~ seconds^%.3f\n", method.c_str(), slope);
                }
                std::printf("-> %s, %s\n", result->csv_path.c_str(), result->png_path.c_str());
                return 0;
            }};
}

}  // namespace lf
