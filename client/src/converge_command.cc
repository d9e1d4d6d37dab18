#include <algorithm>
#include <cmath>
#include <cstdio>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "lf/client/command.h"
#include "lf/client/convergence.h"
#include "lf/client/photon_flags.h"
#include "lf/client/scene_flags.h"
#include "lf/job/job_spec.h"

namespace lf {

namespace {

// Above this share of the smallest measured MSE, the reference's own noise is worth a warning.
constexpr double kReferenceNoiseWarning = 0.05;

// Per configuration its slopes, speed and errors at equal time, the first as the baseline.
void PrintSummary(const ConvergenceResult& result, const std::optional<PixelRect>& region) {
    const TimeRange& t = result.equal_time;
    const ConfigSummary& base = result.configs.front();
    std::printf("\nspp ladders, fitted over %llu to %llu spp (each ladder's rungs there); ",
                (unsigned long long)base.fit.from, (unsigned long long)base.fit.to);
    if (result.equal_time_note.empty()) {
        std::printf(
            "equal time: errors at %.4g s, the longest time every configuration reaches, and "
            "their ratios to %s there and as the geometric mean over %.4g to %.4g s (each curve "
            "interpolated as a power law between its rungs)\n",
            t.to, ConfigName(base.config).c_str(), t.from, t.to);
    } else {
        std::printf("%s: the equal-time columns are nan\n", result.equal_time_note.c_str());
    }
    if (!result.fit_note.empty()) std::printf("(%s)\n", result.fit_note.c_str());
    // The reference's noise adds to every measured MSE (the two are independent), most to the
    // smallest, so it flattens the best configuration's curve and raises its ratios.
    const ConvergenceRow* best = nullptr;
    for (const ConvergenceRow& row : result.rows) {
        if (IsLadderMethod(row.method) && (!best || row.error.rmse < best->error.rmse)) {
            best = &row;
        }
    }
    const double share = best ? std::pow(result.reference_rmse / best->error.rmse, 2) : 0;
    if (share > kReferenceNoiseWarning) {
        std::printf(
            "(the reference's own MSE, estimated from its A/B halves, is %.0f %% of the smallest "
            "measured, %s at %lld spp: it flattens the best curves and raises their ratios; "
            "raise --reference-spp)\n",
            100 * share, ConfigName(best->config).c_str(), (long long)best->budget);
    }
    const std::string rule(142, '-');
    std::printf(
        "%-24s %9s %9s %9s %11s %11s %11s %17s %17s\n%-24s %9s %9s %9s %11s %11s %11s %17s %17s\n",
        "configuration", "slope rel", "slope", "slope", "samples/s", "RMSE", "relMSE", "RMSE ratio",
        "relMSE ratio", "", "RMSE", "RMSE", "per spp", "", "at equal time", "at equal time",
        "at end, mean", "at end, mean");
    std::printf("%s\n", rule.c_str());
    for (const ConfigSummary& c : result.configs) {
        std::printf("%-24s %9.3f %9.3f %9.3f %10.3fM %11.4e %11.4e %8.3f, %6.3f %8.3f, %6.3f\n",
                    ConfigName(c.config).c_str(), c.relative_rmse_slope, c.rmse_slope,
                    c.rmse_spp_slope, c.samples_per_second * 1e-6, c.rmse_at_equal_time,
                    c.relmse_at_equal_time, c.rmse_ratio_at_end, c.rmse_ratio_mean,
                    c.relmse_ratio_at_end, c.relmse_ratio_mean);
    }
    if (!region) return;
    std::printf("\nregion %d,%d %dx%d:\n%-24s %17s %17s\n", region->x0, region->y0, region->width,
                region->height, "configuration", "RMSE at eq. time", "ratio end, mean");
    for (const ConfigSummary& c : result.configs) {
        std::printf("%-24s %17.4e %8.3f, %6.3f\n", ConfigName(c.config).c_str(),
                    c.region_rmse_at_equal_time, c.region_rmse_ratio_at_end,
                    c.region_rmse_ratio_mean);
    }
}

}  // namespace

Command AddConvergeCommand(CLI::App& app) {
    auto options = std::make_shared<ConvergenceOptions>();
    CLI::App* cmd = app.add_subcommand(
        "converge",
        "Measure error against time: render a ladder of budgets (path tracing: 1, 2, 4, ...\n"
        "spp, per configuration of sampler and light strategy; radiosity: doubling patch\n"
        "counts), compare each image with one reference and write DIR/convergence.csv\n"
        "(method,budget,seconds,rmse,relmse,smape,estimated_relmse,sampler,light_sampling),\n"
        "DIR/summary.csv and a table (per configuration: slopes of relative RMSE and RMSE\n"
        "against time over --fit-spp, samples/s, errors at equal time and their ratio to the\n"
        "first configuration) and DIR/convergence.png (log-log error against seconds; gnuplot).\n"
        "Compare configurations with --sampler independent,sobol --light-sampling power,bvh\n"
        "(every pair) or --compare independent/power,sobol/bvh.\n"
        "Without --reference, the most efficient configuration renders one (DIR/reference.exr;\n"
        "the output says which). See docs/convergence.md.");
    cmd->add_option("scene", options->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out_dir, "output directory (created)")->required();
    cmd->add_option("--reference", options->reference_path,
                    "reference OpenEXR of the same size (R,G,B)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--method", options->method,
                    "path, radiosity, both (path and radiosity), whitted (a spp ladder of "
                    "Whitted ray tracing against the path-traced reference: its error levels off "
                    "at the light transport it leaves out), or a comma-separated list of the "
                    "spp-ladder methods path, light, bdpt and ppm (e.g. path,bdpt,ppm: one ladder "
                    "per method and configuration; budget = spp, light paths per pixel for light, "
                    "photon passes for ppm)")
        ->capture_default_str();
    AddPhotonFlags(cmd, options->ppm);
    AddCameraFlag(cmd, options->scene);
    AddFilterFlag(cmd, options->scene);
    AddResolutionFlag(cmd, options->scene,
                      "image size WxH, or N for N x N, instead of the scene's");
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
    auto samplers = std::make_shared<std::string>(SamplerTypeName(options->configs[0].sampler));
    auto strategies =
        std::make_shared<std::string>(LightStrategyName(options->configs[0].light_strategy));
    auto compare = std::make_shared<std::string>();
    auto fit = std::make_shared<std::string>();
    CLI::Option* sampler_option =
        cmd->add_option("--sampler", *samplers,
                        absl::StrCat("samplers of the path ladders, comma-separated: sobol "
                                     "(Owen-scrambled Sobol points, low-discrepancy, so on smooth "
                                     "integrands the error falls faster than spp^-1/2) and "
                                     "independent (hashed random numbers, error as spp^-1/2, for "
                                     "comparison); with --light-sampling, every pair is a "
                                     "configuration. Default ",
                                     *samplers))
            ->type_name("independent|sobol,...");
    CLI::Option* lights_option =
        cmd->add_option("--light-sampling", *strategies,
                        absl::StrCat("light strategies of the path ladders, comma-separated: bvh "
                                     "(a light BVH weighs every light by its importance at the "
                                     "shading point; triangles and spheres that look large are "
                                     "sampled by the solid angle they subtend) and power (a light "
                                     "with probability proportional to its power, a point on it "
                                     "by area, for comparison). Default ",
                                     *strategies))
            ->type_name("power|bvh,...");
    cmd->add_option("--compare", *compare,
                    "configurations of the path ladders, SAMPLER/LIGHTS, comma-separated, e.g. "
                    "independent/power,sobol/bvh; the first is the baseline of the ratios")
        ->type_name("SAMPLER/LIGHTS,...")
        ->excludes(sampler_option)
        ->excludes(lights_option);
    auto region = std::make_shared<std::string>();
    cmd->add_option("--region", *region,
                    "X,Y,W,H: also measure the errors of this rectangle of the image (pixels from "
                    "the top left; e.g. the caustic under a glass sphere), in both CSVs and the "
                    "table")
        ->type_name("X,Y,W,H");
    cmd->add_option("--fit-spp", *fit,
                    "FROM:TO: the rungs the slopes, speeds and equal-time errors use (default "
                    "16:1024, or the whole ladder when that holds fewer than two rungs)")
        ->type_name("FROM:TO");
    return {
        cmd, [cmd, options, samplers, strategies, compare, fit, region] {
            absl::StatusOr<std::vector<RenderConfig>> configs =
                compare->empty() ? ConfigProduct(*samplers, *strategies)
                                 : ParseConfigList(*compare);
            if (!configs.ok()) return ReportError(configs.status());
            options->configs = *configs;
            // The photon flags apply when some ladder is ppm's.
            const bool ppm =
                absl::StrContains(options->method, "ppm") ||
                std::any_of(configs->begin(), configs->end(),
                            [](const RenderConfig& c) { return c.method == Method::kPpm; });
            if (absl::Status s = CheckPhotonFlagsApply(*cmd, ppm ? "ppm" : options->method);
                !s.ok()) {
                return ReportError(s);
            }
            if (!region->empty()) {
                absl::StatusOr<PixelRect> rect = ParseRegion(*region);
                if (!rect.ok()) return ReportError(rect.status());
                options->region = *rect;
            }
            if (!fit->empty()) {
                absl::StatusOr<SppRange> range = ParseSppRange(*fit);
                if (!range.ok()) return ReportError(range.status());
                options->fit_spp = *range;
                options->fit_spp_given = true;
            }
            absl::StatusOr<ConvergenceResult> result = RunConvergence(*options);
            if (!result.ok()) return ReportError(result.status());
            std::printf("%s", result->reference.c_str());
            if (result->reference_rmse > 0) {
                std::printf(" (its own RMSE estimate from A/B: %.3e)", result->reference_rmse);
            }
            std::printf("\n%s\n", kConvergenceCsvHeader);
            for (const ConvergenceRow& row : result->rows) {
                std::printf("%s,%lld,%.4f,%.4e,%.4e,%.4e,%s,%s,%s,%s\n",
                            std::string(MethodName(row.method)).c_str(), (long long)row.budget,
                            row.seconds, row.error.rmse, row.error.relmse, row.error.smape,
                            EstimatedRelMseField(row).c_str(), SamplerTypeName(row.config.sampler),
                            LightSamplingField(row), RegionFields(row).c_str());
            }
            if (!result->configs.empty()) PrintSummary(*result, options->region);
            if (result->radiosity_slope != 0) {
                std::printf("radiosity: sqrt(relmse) ~ seconds^%.3f\n", result->radiosity_slope);
            }
            std::printf("-> %s", result->csv_path.c_str());
            for (const std::string* path :
                 {&result->summary_path, &result->png_path, &result->reference_exr_path}) {
                if (!path->empty()) std::printf(", %s", path->c_str());
            }
            std::printf("\n");
            return 0;
        }};
}

}  // namespace lf
