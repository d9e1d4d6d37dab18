#include "lf/client/convergence.h"

#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "lf/core/camera.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/scene_loader.h"
#include "lf/job/method_registry.h"
#include "lf/job/render_metadata.h"
#include "lf/job/splat_settings.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiosity.h"
#include "lf/local/local_executor.h"
#include "lf/local/method_factory.h"
#include "lf/local/method_render.h"

extern char** environ;

namespace lf {

bool IsLadderMethod(Method method) {
    return method == Method::kPath || Info(method).work == WorkKind::kSplatPasses;
}

std::string ConfigName(const RenderConfig& config) {
    return absl::StrCat(config.method == Method::kPath ? "" : MethodName(config.method),
                        config.method == Method::kPath ? "" : "/", SamplerTypeName(config.sampler),
                        "/", LightStrategyName(config.light_strategy));
}

namespace {

// Comma-separated names, each known to `from_name`, none twice.
template <class T, class FromName>
absl::StatusOr<std::vector<T>> ParseNames(const std::string& flag, const std::string& list,
                                          FromName from_name, const std::string& expected) {
    std::vector<T> out;
    const std::vector<std::string> names = absl::StrSplit(list, ',');
    for (const std::string& name : names) {
        const std::optional<T> value = from_name(name);
        if (!value) {
            return absl::InvalidArgumentError(
                absl::StrCat(flag, " ", list, ": \"", name, "\" is not ", expected));
        }
        if (std::find(out.begin(), out.end(), *value) != out.end()) {
            return absl::InvalidArgumentError(
                absl::StrCat(flag, " ", list, ": \"", name, "\" is listed twice"));
        }
        out.push_back(*value);
    }
    return out;
}

std::optional<RenderConfig> ConfigFromName(const std::string& name) {
    std::vector<std::string> parts = absl::StrSplit(name, '/');
    if (parts.size() == 2) parts.insert(parts.begin(), std::string(MethodName(Method::kPath)));
    const std::optional<Method> method = FindMethod(parts.size() == 3 ? parts[0] : "");
    if (!method || !IsLadderMethod(*method)) return std::nullopt;
    const std::optional<SamplerType> sampler = SamplerTypeFromName(parts[1]);
    const std::optional<LightStrategy> strategy = LightStrategyFromName(parts[2]);
    if (!sampler || !strategy) return std::nullopt;
    return RenderConfig{*method, *sampler, *strategy};
}

}  // namespace

absl::StatusOr<std::vector<RenderConfig>> ParseConfigList(const std::string& list) {
    return ParseNames<RenderConfig>("--compare", list, ConfigFromName,
                                    "[METHOD/]SAMPLER/LIGHTS with METHOD path, light, bdpt or ppm, "
                                    "SAMPLER independent or sobol and LIGHTS power or bvh, e.g. "
                                    "sobol/bvh or bdpt/sobol/bvh");
}

absl::StatusOr<std::vector<RenderConfig>> ConfigProduct(const std::string& samplers,
                                                        const std::string& light_strategies) {
    absl::StatusOr<std::vector<SamplerType>> s =
        ParseNames<SamplerType>("--sampler", samplers, SamplerTypeFromName, "independent or sobol");
    if (!s.ok()) return s.status();
    absl::StatusOr<std::vector<LightStrategy>> l = ParseNames<LightStrategy>(
        "--light-sampling", light_strategies, LightStrategyFromName, "power or bvh");
    if (!l.ok()) return l.status();
    std::vector<RenderConfig> out;
    for (SamplerType sampler : *s) {
        for (LightStrategy strategy : *l) out.push_back({Method::kPath, sampler, strategy});
    }
    return out;
}

absl::StatusOr<SppRange> ParseSppRange(const std::string& text) {
    const std::vector<std::string> parts = absl::StrSplit(text, ':');
    SppRange range;
    if (parts.size() != 2 || !absl::SimpleAtoi(parts[0], &range.from) ||
        !absl::SimpleAtoi(parts[1], &range.to) || range.from < 1 || range.from >= range.to) {
        return absl::InvalidArgumentError(absl::StrCat(
            "--fit-spp ", text, ": expected FROM:TO, spp with 1 <= FROM < TO, e.g. 16:1024"));
    }
    return range;
}

absl::StatusOr<PixelRect> ParseRegion(const std::string& text) {
    const std::vector<std::string> parts = absl::StrSplit(text, ',');
    PixelRect r;
    if (parts.size() != 4 || !absl::SimpleAtoi(parts[0], &r.x0) ||
        !absl::SimpleAtoi(parts[1], &r.y0) || !absl::SimpleAtoi(parts[2], &r.width) ||
        !absl::SimpleAtoi(parts[3], &r.height) || r.x0 < 0 || r.y0 < 0 || r.width < 1 ||
        r.height < 1) {
        return absl::InvalidArgumentError(
            absl::StrCat("--region ", text,
                         ": expected X,Y,W,H in pixels (X, Y >= 0; W, H >= 1), e.g. 40,80,32,16"));
    }
    return r;
}

namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// gnuplot reads single-quoted strings literally except for '' (one quote).
std::string GnuplotQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
    return out + "'";
}

// What the plot's first panel and the relative slopes use: relmse weighs every pixel by its
// own brightness, where RMSE is dominated by the few pixels on the light's edges
// (docs/convergence.md), and its square root falls as time^-1/2 for plain Monte Carlo.
double RelativeRmse(const ConvergenceRow& row) { return std::sqrt(row.error.relmse); }

// A curve of the plot and the legend's slope: a path configuration's or radiosity's.
std::string CurveName(const ConvergenceRow& row) {
    return IsLadderMethod(row.method) ? ConfigName(row.config)
                                      : std::string(MethodName(row.method));
}

}  // namespace

const char* LightSamplingField(const ConvergenceRow& row) {
    return Info(row.method).work == WorkKind::kRadiosity
               ? ""
               : LightStrategyName(row.config.light_strategy);
}

std::string EstimatedRelMseField(const ConvergenceRow& row) {
    return row.estimated_relmse ? absl::StrFormat("%.6e", *row.estimated_relmse) : "";
}

std::string RegionFields(const ConvergenceRow& row) {
    return row.region_error
               ? absl::StrFormat("%.6e,%.6e", row.region_error->rmse, row.region_error->relmse)
               : ",";
}

namespace {

// gnuplot draws the plot (a Debian package, deploy/install-deps.sh): relative RMSE and RMSE
// against time side by side, one curve per configuration and radiosity. The script stays next
// to the PNG so the figure can be restyled without rendering again.
absl::Status Plot(const ConvergenceResult& result, const std::string& script_path) {
    std::ofstream gp(script_path);
    gp << "set terminal pngcairo size 1400,600 font 'sans,11'\n"
       << "set output " << GnuplotQuote(result.png_path) << "\n";
    int index = 0;
    std::vector<std::string> relative_plot, rmse_plot;
    auto add_curve = [&](const std::string& name, Method method, double relative_slope,
                         const std::string& rmse_slope) {
        const std::string block = absl::StrCat("$curve", index++);
        gp << block << " << EOD\n";
        for (const ConvergenceRow& row : result.rows) {
            if (CurveName(row) == name && row.method == method) {
                gp << row.seconds << " " << RelativeRmse(row) << " " << row.error.rmse << "\n";
            }
        }
        gp << "EOD\n";
        const std::string title = method == Method::kPath      ? "path tracing, " + name
                                  : method == Method::kPpm     ? name + " (biased: falls slower)"
                                  : IsLadderMethod(method)     ? name
                                  : method == Method::kWhitted ? "whitted (biased: levels off)"
                                                               : "radiosity";
        relative_plot.push_back(absl::StrFormat(
            "%s using 1:2 with linespoints pt 7 title %s", block,
            GnuplotQuote(absl::StrFormat("%s (slope %.2f)", title, relative_slope))));
        rmse_plot.push_back(absl::StrFormat(
            "%s using 1:3 with linespoints pt 7 title %s", block,
            GnuplotQuote(rmse_slope.empty() ? title : title + " (slope " + rmse_slope + ")")));
    };
    for (const ConfigSummary& c : result.configs) {
        add_curve(ConfigName(c.config), c.config.method, c.relative_rmse_slope,
                  absl::StrFormat("%.2f", c.rmse_slope));
    }
    const auto any = [&](Method method) {
        return std::any_of(result.rows.begin(), result.rows.end(),
                           [&](const ConvergenceRow& r) { return r.method == method; });
    };
    if (any(Method::kRadiosity)) {
        add_curve("radiosity", Method::kRadiosity, result.radiosity_slope, "");
    }
    if (any(Method::kWhitted)) add_curve("whitted", Method::kWhitted, result.whitted_slope, "");
    std::string title = "Error against time";
    if (!result.configs.empty()) {
        const SppRange& fit = result.configs.front().fit;
        absl::StrAppendFormat(&title, "; path slopes fitted over %d to %d spp", fit.from, fit.to);
    }
    gp << "set multiplot layout 1,2 title " << GnuplotQuote(title) << "\n"
       << "set logscale xy\nset grid\nset key bottom left\n"
       << "set xlabel 'wall-clock seconds'\n"
       << "set ylabel 'relative RMSE, sqrt(relmse), against the reference'\n"
       << "plot " << absl::StrJoin(relative_plot, ", ") << "\n"
       << "set ylabel 'RMSE against the reference (radiance)'\n"
       << "plot " << absl::StrJoin(rmse_plot, ", ") << "\n"
       << "unset multiplot\n";
    gp.close();
    if (!gp) return absl::InternalError(script_path + ": cannot write");

    const char* argv[] = {"gnuplot", script_path.c_str(), nullptr};
    pid_t pid;
    if (posix_spawnp(&pid, "gnuplot", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) {
        return absl::FailedPreconditionError(
            "cannot run gnuplot to draw " + result.png_path +
            " (install gnuplot-nox; deploy/install-deps.sh does); convergence.csv is written");
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        return absl::InternalError("gnuplot failed on " + script_path);
    }
    return absl::OkStatus();
}

absl::Status WriteCsv(const ConvergenceResult& result) {
    std::ofstream csv(result.csv_path);
    csv << kConvergenceCsvHeader << "\n";
    for (const ConvergenceRow& row : result.rows) {
        csv << absl::StrFormat("%s,%d,%.4f,%.6e,%.6e,%.6e,%s,%s,%s,%s\n", MethodName(row.method),
                               row.budget, row.seconds, row.error.rmse, row.error.relmse,
                               row.error.smape, EstimatedRelMseField(row),
                               SamplerTypeName(row.config.sampler), LightSamplingField(row),
                               RegionFields(row));
    }
    csv.close();
    if (!csv) return absl::PermissionDeniedError(result.csv_path + ": cannot write");
    return absl::OkStatus();
}

absl::Status WriteSummaryCsv(const ConvergenceResult& result) {
    std::ofstream csv(result.summary_path);
    csv << kSummaryCsvHeader << "\n";
    for (const ConfigSummary& c : result.configs) {
        csv << absl::StrFormat(
            "%s,%s,%d,%d,%.4f,%.4f,%.6e,%.6g,%.6g,%.6e,%.6e,%.4f,%.4f,%.4f,%.4f,%.4f,%.6e,%.4f,%."
            "4f,"
            "%s\n",
            SamplerTypeName(c.config.sampler), LightStrategyName(c.config.light_strategy),
            c.fit.from, c.fit.to, c.relative_rmse_slope, c.rmse_slope, c.samples_per_second,
            result.equal_time.from, result.equal_time.to, c.rmse_at_equal_time,
            c.relmse_at_equal_time, c.rmse_ratio_at_end, c.rmse_ratio_mean, c.relmse_ratio_at_end,
            c.relmse_ratio_mean, c.rmse_spp_slope, c.region_rmse_at_equal_time,
            c.region_rmse_ratio_at_end, c.region_rmse_ratio_mean, MethodName(c.config.method));
    }
    csv.close();
    if (!csv) return absl::PermissionDeniedError(result.summary_path + ": cannot write");
    return absl::OkStatus();
}

// The path ladder's rungs: 1, 2, 4, ... up to max_spp.
std::vector<uint64_t> Ladder(uint64_t max_spp) {
    std::vector<uint64_t> rungs;
    for (uint64_t spp = 1; spp <= max_spp; spp *= 2) rungs.push_back(spp);
    return rungs;
}

// The ladder's rungs the slopes are fitted over, as the first and last of them: --fit-spp's
// when it holds two rungs, else (when it was not given) the whole ladder, with a note for the
// output.
absl::StatusOr<SppRange> FitRange(const ConvergenceOptions& options, std::string* note) {
    std::vector<uint64_t> inside;
    for (uint64_t spp : Ladder(options.max_spp)) {
        if (spp >= options.fit_spp.from && spp <= options.fit_spp.to) inside.push_back(spp);
    }
    if (inside.size() >= 2) return SppRange{inside.front(), inside.back()};
    const std::string why =
        absl::StrFormat("--fit-spp %d:%d holds fewer than two rungs of the ladder 1 to %d spp",
                        options.fit_spp.from, options.fit_spp.to, options.max_spp);
    if (options.fit_spp_given) {
        return absl::InvalidArgumentError(why + "; widen it or raise --max-spp");
    }
    *note = why + ": the slopes are fitted over the whole ladder";
    return SppRange{1, Ladder(options.max_spp).back()};
}

// Slopes, speed and curves of one configuration's rungs within `fit`.
struct FittedLadder {
    ConfigSummary summary;
    ErrorCurve rmse, relmse;
    ErrorCurve region_rmse;  // with --region
};

absl::StatusOr<FittedLadder> FitLadder(const ConvergenceResult& result, const RenderConfig& config,
                                       const SppRange& fit, int64_t pixels) {
    FittedLadder out;
    out.summary.config = config;
    out.summary.fit = fit;
    ErrorCurve relative, by_spp;
    double samples = 0, seconds = 0;
    for (const ConvergenceRow& row : result.rows) {
        if (!IsLadderMethod(row.method) || !(row.config == config) ||
            uint64_t(row.budget) < fit.from || uint64_t(row.budget) > fit.to) {
            continue;
        }
        relative.push_back({row.seconds, RelativeRmse(row)});
        out.rmse.push_back({row.seconds, row.error.rmse});
        by_spp.push_back({double(row.budget), row.error.rmse});
        out.relmse.push_back({row.seconds, row.error.relmse});
        if (row.region_error) out.region_rmse.push_back({row.seconds, row.region_error->rmse});
        samples += double(row.budget) * double(pixels);
        seconds += row.seconds;
    }
    const std::string name = ConfigName(config);
    absl::StatusOr<double> relative_slope = LogLogSlope(relative);
    absl::StatusOr<double> rmse_slope = LogLogSlope(out.rmse);
    absl::StatusOr<double> spp_slope = LogLogSlope(by_spp);
    for (const absl::StatusOr<double>* slope : {&relative_slope, &rmse_slope, &spp_slope}) {
        if (!slope->ok()) {
            return absl::InvalidArgumentError(absl::StrCat(name, ": no slope from its rungs of ",
                                                           fit.from, " to ", fit.to, " spp (",
                                                           slope->status().message(), ")"));
        }
    }
    out.summary.relative_rmse_slope = *relative_slope;
    out.summary.rmse_slope = *rmse_slope;
    out.summary.rmse_spp_slope = *spp_slope;
    out.summary.samples_per_second = seconds > 0 ? samples / seconds : 0;
    return out;
}

// Per configuration its slopes and speed, and the errors at equal time against the first: each
// curve (its fit range's rungs) interpolated as a power law between its own rungs, over the
// times every configuration covers.
absl::Status Summarize(const ConvergenceOptions& options, const std::vector<RenderConfig>& configs,
                       int64_t pixels, ConvergenceResult& result) {
    absl::StatusOr<SppRange> fit = FitRange(options, &result.fit_note);
    if (!fit.ok()) return fit.status();
    std::vector<FittedLadder> ladders;
    std::vector<ErrorCurve> rmse_curves;
    for (const RenderConfig& config : configs) {
        absl::StatusOr<FittedLadder> ladder = FitLadder(result, config, *fit, pixels);
        if (!ladder.ok()) return ladder.status();
        rmse_curves.push_back(ladder->rmse);
        ladders.push_back(*std::move(ladder));
    }
    absl::StatusOr<TimeRange> range = CommonTimeRange(rmse_curves);
    if (!range.ok()) {
        result.equal_time_note = absl::StrCat("no equal-time comparison over ", fit->from, " to ",
                                              fit->to, " spp: ", range.status().message(),
                                              "; widen --fit-spp or raise --max-spp");
        constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
        for (FittedLadder& ladder : ladders) {
            ConfigSummary& s = ladder.summary;
            s.rmse_at_equal_time = s.relmse_at_equal_time = kNone;
            // The baseline's ratios to itself stay 1.
            if (!result.configs.empty()) {
                s.rmse_ratio_at_end = s.relmse_ratio_at_end = kNone;
                s.rmse_ratio_mean = s.relmse_ratio_mean = kNone;
            }
            result.configs.push_back(s);
        }
        return absl::OkStatus();
    }
    result.equal_time = *range;
    const FittedLadder& base = ladders.front();
    for (FittedLadder& ladder : ladders) {
        ConfigSummary& s = ladder.summary;
        absl::StatusOr<double> rmse = ErrorAtTime(ladder.rmse, range->to);
        absl::StatusOr<double> relmse = ErrorAtTime(ladder.relmse, range->to);
        absl::StatusOr<double> rmse_mean = MeanRatioOverTime(base.rmse, ladder.rmse, *range);
        absl::StatusOr<double> relmse_mean = MeanRatioOverTime(base.relmse, ladder.relmse, *range);
        for (const absl::StatusOr<double>* v : {&rmse, &relmse, &rmse_mean, &relmse_mean}) {
            if (!v->ok()) return v->status();
        }
        s.rmse_at_equal_time = *rmse;
        s.relmse_at_equal_time = *relmse;
        s.rmse_ratio_mean = *rmse_mean;
        s.relmse_ratio_mean = *relmse_mean;
        if (!ladder.region_rmse.empty()) {
            absl::StatusOr<double> region = ErrorAtTime(ladder.region_rmse, range->to);
            absl::StatusOr<double> region_mean =
                MeanRatioOverTime(base.region_rmse, ladder.region_rmse, *range);
            for (const absl::StatusOr<double>* v : {&region, &region_mean}) {
                if (!v->ok()) return v->status();
            }
            s.region_rmse_at_equal_time = *region;
            s.region_rmse_ratio_mean = *region_mean;
        }
        result.configs.push_back(s);
    }
    for (ConfigSummary& s : result.configs) {
        const ConfigSummary& first = result.configs.front();
        s.rmse_ratio_at_end = s.rmse_at_equal_time / first.rmse_at_equal_time;
        s.relmse_ratio_at_end = s.relmse_at_equal_time / first.relmse_at_equal_time;
        s.region_rmse_ratio_at_end = s.region_rmse_at_equal_time / first.region_rmse_at_equal_time;
    }
    return absl::OkStatus();
}

// The ladders' configurations: --method's ladder methods (path for "both"; none for radiosity
// and whitted) times the sampler and light configurations, or --compare's own when they name
// their methods.
absl::StatusOr<std::vector<RenderConfig>> LadderConfigs(const ConvergenceOptions& options) {
    if (options.configs.empty()) return absl::InvalidArgumentError("no configuration to render");
    const std::optional<Method> single = FindMethod(options.method);
    if (single == Method::kRadiosity || single == Method::kWhitted) {
        return std::vector<RenderConfig>{};
    }
    const std::string list =
        options.method == "both" ? std::string(MethodName(Method::kPath)) : options.method;
    absl::StatusOr<std::vector<Method>> methods = ParseNames<Method>(
        "--method", list,
        [](const std::string& name) -> std::optional<Method> {
            const std::optional<Method> method = FindMethod(name);
            if (!method || !IsLadderMethod(*method)) return std::nullopt;
            return method;
        },
        "path, radiosity, both, whitted or a list of path, light, bdpt and ppm");
    if (!methods.ok()) return methods.status();
    const bool explicit_methods =
        std::any_of(options.configs.begin(), options.configs.end(),
                    [](const RenderConfig& c) { return c.method != Method::kPath; });
    if (explicit_methods) {
        if (*methods != std::vector<Method>{Method::kPath}) {
            return absl::InvalidArgumentError(absl::StrCat(
                "--method ", options.method,
                " with --compare configurations that name their methods: give the methods in "
                "one place"));
        }
        return options.configs;
    }
    std::vector<RenderConfig> out;
    for (const Method method : *methods) {
        for (RenderConfig config : options.configs) {
            config.method = method;
            out.push_back(config);
        }
    }
    return out;
}

}  // namespace

absl::StatusOr<ConvergenceResult> RunConvergence(const ConvergenceOptions& options) {
    absl::StatusOr<std::vector<RenderConfig>> ladder_configs = LadderConfigs(options);
    if (!ladder_configs.ok()) return ladder_configs.status();
    const std::vector<RenderConfig>& configs = *ladder_configs;
    if (absl::Status s = CheckPhotonSettings(options.ppm); !s.ok()) return s;
    const bool path = !configs.empty();
    const bool with_radiosity =
        FindMethod(options.method) == Method::kRadiosity || options.method == "both";
    std::string unused_note;
    if (path) {
        // Refuse a bad --fit-spp before rendering anything.
        if (absl::StatusOr<SppRange> fit = FitRange(options, &unused_note); !fit.ok()) {
            return fit.status();
        }
    }
    std::error_code ec;
    std::filesystem::create_directories(options.out_dir, ec);
    if (ec) return absl::PermissionDeniedError(options.out_dir + ": " + ec.message());

    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    if (with_radiosity) {
        if (const std::string why = RadiosityLimitation(*scene); !why.empty()) {
            return absl::InvalidArgumentError(absl::StrCat(
                "--method ", options.method, ": radiosity cannot model this scene: ", why));
        }
        // With `both`, the path ladder renders radiosity's tessellation too: the comparison is
        // of the methods on one geometry.
        PrepareSceneFor(Method::kRadiosity, *scene);
    }
    auto log = NamedLogger("converge");
    const std::string job_id = "converge-" + scene->content_hash.substr(0, 8);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    const int64_t pixels = int64_t(camera.width()) * camera.height();
    if (const std::optional<PixelRect>& r = options.region;
        r && (int64_t(r->x0) + r->width > camera.width() ||
              int64_t(r->y0) + r->height > camera.height())) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "--region %d,%d,%d,%d leaves the %dx%d image (--resolution sets its size)", r->x0,
            r->y0, r->width, r->height, camera.width(), camera.height()));
    }
    // The row's errors against the reference: the whole image's and, with --region, the
    // region's.
    const auto compare = [&](const Image& image, const Image& reference,
                             ConvergenceRow& row) -> absl::Status {
        absl::StatusOr<ImageError> error = CompareImages(image, reference);
        if (!error.ok()) return error.status();
        row.error = *error;
        if (options.region) {
            absl::StatusOr<ImageError> region =
                CompareImageRegion(image, reference, *options.region);
            if (!region.ok()) return region.status();
            row.region_error = *region;
        }
        return absl::OkStatus();
    };

    // A rung of a ladder (budget = spp: light paths per pixel for light, photon passes for
    // ppm), as `render` makes it.
    auto render_path = [&](const RenderConfig& config, uint64_t spp, uint64_t seed) {
        MethodRenderSettings settings;
        settings.max_depth = options.max_depth;
        settings.seed = seed;
        settings.sampler = config.sampler;
        settings.light_strategy = config.light_strategy;
        settings.threads = options.threads;
        settings.ppm = options.ppm;
        return RenderWithMethod(config.method, **embree, camera, settings, spp);
    };

    ConvergenceResult result;
    const std::filesystem::path dir(options.out_dir);
    result.csv_path = (dir / "convergence.csv").string();
    result.png_path = (dir / "convergence.png").string();

    // The path ladders first: with no reference given, the most efficient of them renders it.
    // Rung by rung, every configuration in turn, so that a change in the machine's load (it is
    // often shared) falls on all of them alike; the rows stay ladder by ladder.
    const std::vector<uint64_t> rungs = path ? Ladder(options.max_spp) : std::vector<uint64_t>{};
    const size_t path_rows = rungs.size() * configs.size();
    result.rows.resize(path_rows);
    std::vector<Image> images(path_rows);  // of result.rows, until the reference is known
    for (size_t k = 0; k < rungs.size(); ++k) {
        for (size_t c = 0; c < configs.size(); ++c) {
            const RenderConfig& config = configs[c];
            absl::StatusOr<RenderOutput> out = render_path(config, rungs[k], options.seed);
            if (!out.ok()) return out.status();
            log->info("job={} {} {} spp: {:.3f} s", job_id, ConfigName(config), rungs[k],
                      out->seconds);
            ConvergenceRow& row = result.rows[c * rungs.size() + k];
            row.method = config.method;
            row.config = config;
            row.budget = int64_t(rungs[k]);
            row.seconds = out->seconds;
            // Images estimate their own error from 2 spp on.
            if (rungs[k] >= 2) {
                if (absl::StatusOr<double> e = EstimatedRelMse(out->image); e.ok()) {
                    row.estimated_relmse = *e;
                }
            }
            images[c * rungs.size() + k] = std::move(out->image);
        }
    }

    Image reference;
    if (!options.reference_path.empty()) {
        absl::StatusOr<ExrFile> file = ReadExr(options.reference_path);
        if (!file.ok()) return file.status();
        reference = std::move(file->image);
        if (reference.width() != camera.width() || reference.height() != camera.height()) {
            return absl::InvalidArgumentError(
                absl::StrCat(options.reference_path, " is ", reference.width(), "x",
                             reference.height(), " but the renders are ", camera.width(), "x",
                             camera.height(), " (set --resolution)"));
        }
        result.reference = "reference " + options.reference_path;
    } else {
        // The configuration whose top rung has the least estimated MSE (A/B halves) times
        // seconds: the least error for the reference's time. Only the unbiased methods that see
        // everything qualify: path and bdpt (ppm is biased; light tracing cannot see mirrors,
        // glass or the sky). Without such a ladder, the path tracer with the first
        // configuration's sampler and lights.
        RenderConfig best = options.configs.front();
        best.method = Method::kPath;
        std::string why = "the first configuration";
        double best_cost = std::numeric_limits<double>::infinity();
        for (size_t i = 0; i < path_rows; ++i) {
            if (uint64_t(result.rows[i].budget) != rungs.back()) continue;
            const Method method = result.rows[i].method;
            if (method != Method::kPath && method != Method::kBdpt) continue;
            absl::StatusOr<double> mse = EstimatedMse(images[i]);
            if (!mse.ok()) continue;
            const double cost = *mse * result.rows[i].seconds;
            if (cost < best_cost) {
                best_cost = cost;
                best = result.rows[i].config;
                why = absl::StrFormat(
                    "the most efficient at %d spp by its own A/B error estimate: estimated MSE "
                    "x seconds",
                    rungs.back());
            }
        }
        // Another seed, so the reference's noise is independent of the ladders'.
        const uint64_t seed = options.seed + 1;
        const std::string kind =
            best.method == Method::kPath ? "path-traced" : std::string(MethodName(best.method));
        log->info("job={} no reference given: rendering a {} one with {} at {} spp", job_id, kind,
                  ConfigName(best), options.reference_spp);
        absl::StatusOr<RenderOutput> out = render_path(best, options.reference_spp, seed);
        if (!out.ok()) return out.status();
        result.reference = absl::StrFormat(
            "no reference given: own %s reference, %d spp, %s (%s), seed %d, %.1f s", kind,
            options.reference_spp, ConfigName(best), why, seed, out->seconds);
        RenderMetadata metadata;
        metadata.scene_hash = scene->content_hash;
        metadata.camera = options.scene.camera;
        metadata.method = std::string(MethodName(best.method));
        metadata.spp = options.reference_spp;
        metadata.seed = seed;
        metadata.max_depth = options.max_depth;
        metadata.sampler = best.sampler;
        metadata.light_strategy = best.light_strategy;
        metadata.filter = scene->camera.filter;
        metadata.seconds = out->seconds;
        metadata.stats = out->stats;
        absl::StatusOr<RenderDescription> description = DescribeRender(metadata, out->image, true);
        if (!description.ok()) return description.status();
        description->attributes["lightfarm.converge.reference"] = result.reference;
        result.reference_exr_path = (dir / "reference.exr").string();
        if (absl::Status s =
                WriteExr(result.reference_exr_path, out->image, description->attributes);
            !s.ok()) {
            return s;
        }
        reference = std::move(out->image);
    }
    if (absl::StatusOr<double> mse = EstimatedMse(reference); mse.ok()) {
        result.reference_rmse = std::sqrt(*mse);
    }
    for (size_t i = 0; i < result.rows.size(); ++i) {
        if (absl::Status s = compare(images[i], reference, result.rows[i]); !s.ok()) return s;
        log->info("job={} {} {} spp: rmse {:.4e}", job_id, ConfigName(result.rows[i].config),
                  result.rows[i].budget, result.rows[i].error.rmse);
    }
    images.clear();

    if (with_radiosity) {
        for (int64_t patches = options.min_patches; patches <= options.max_patches; patches *= 2) {
            const auto start = Clock::now();
            RadiositySettings solve;
            solve.patches = patches;
            solve.tolerance = options.radiosity_tolerance;
            absl::StatusOr<RadiosityOptions> ro = RadiosityOptionsOf(solve, 0);
            if (!ro.ok()) return ro.status();
            ro->threads = options.threads;
            absl::StatusOr<std::unique_ptr<RadiosityRenderer>> radiosity =
                PrepareRadiosity(**embree, *ro);
            if (!radiosity.ok()) return radiosity.status();
            RenderSettings settings;
            settings.spp = options.radiosity_spp;
            settings.seed = options.seed;
            settings.threads = options.threads;
            settings.sampler = options.configs.front().sampler;
            absl::StatusOr<RenderOutput> out = RenderImage(camera, **radiosity, settings);
            if (!out.ok()) return out.status();
            // A radiosity image's A/B halves see only the display's sampling, not the
            // solution's error: no estimate.
            ConvergenceRow row;
            row.method = Method::kRadiosity;
            row.config = options.configs.front();
            row.budget = (*radiosity)->report().patches;
            row.seconds = SecondsSince(start);
            if (absl::Status s = compare(out->image, reference, row); !s.ok()) return s;
            result.rows.push_back(row);
            log->info("job={} radiosity {} patches: {:.3f} s, rmse {:.4e}", job_id, row.budget,
                      row.seconds, row.error.rmse);
        }
    }
    if (FindMethod(options.method) == Method::kWhitted) {
        // Whitted's ladder against the same reference: its error falls with the pixel and
        // area-light sampling, then levels off at what it leaves out (WhittedMissingTerms).
        const RenderConfig& config = options.configs.front();
        absl::StatusOr<std::unique_ptr<RadianceEstimator>> whitted =
            MakeRayTracer(Method::kWhitted, **embree, options.max_depth, config.light_strategy);
        if (!whitted.ok()) return whitted.status();
        for (uint64_t spp : Ladder(options.max_spp)) {
            RenderSettings settings;
            settings.spp = spp;
            settings.seed = options.seed;
            settings.threads = options.threads;
            settings.sampler = config.sampler;
            settings.light_strategy = config.light_strategy;
            absl::StatusOr<RenderOutput> out = RenderImage(camera, **whitted, settings);
            if (!out.ok()) return out.status();
            ConvergenceRow row;
            row.method = Method::kWhitted;
            row.config = config;
            row.budget = int64_t(spp);
            row.seconds = out->seconds;
            if (absl::Status s = compare(out->image, reference, row); !s.ok()) return s;
            if (spp >= 2) {
                if (absl::StatusOr<double> e = EstimatedRelMse(out->image); e.ok()) {
                    row.estimated_relmse = *e;
                }
            }
            result.rows.push_back(row);
            log->info("job={} whitted {} spp: {:.3f} s, rmse {:.4e}", job_id, spp, row.seconds,
                      row.error.rmse);
        }
        std::vector<std::pair<double, double>> points;
        for (const ConvergenceRow& row : result.rows) {
            if (row.method == Method::kWhitted) points.push_back({row.seconds, RelativeRmse(row)});
        }
        // A ladder too fast to time has no slope; the curve is drawn all the same.
        if (absl::StatusOr<double> slope = LogLogSlope(points); slope.ok()) {
            result.whitted_slope = *slope;
        }
    }
    if (absl::Status s = WriteCsv(result); !s.ok()) return s;

    if (path) {
        if (absl::Status s = Summarize(options, configs, pixels, result); !s.ok()) return s;
        result.summary_path = (dir / "summary.csv").string();
        if (absl::Status s = WriteSummaryCsv(result); !s.ok()) return s;
    }
    if (with_radiosity) {
        std::vector<std::pair<double, double>> points;
        for (const ConvergenceRow& row : result.rows) {
            if (row.method == Method::kRadiosity)
                points.push_back({row.seconds, RelativeRmse(row)});
        }
        absl::StatusOr<double> slope = LogLogSlope(points);
        if (!slope.ok()) {
            return absl::InvalidArgumentError(
                absl::StrCat("radiosity: no slope from its ladder (", slope.status().message(),
                             "); widen it with --min-patches and --max-patches"));
        }
        result.radiosity_slope = *slope;
    }
    const std::string script = (dir / "convergence.gp").string();
    if (absl::Status s = Plot(result, script); !s.ok()) return s;
    return result;
}

}  // namespace lf
