#include "convergence.h"

#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "lf/core/camera.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiosity.h"
#include "lf/local/local_executor.h"
#include "local_render.h"
#include "radiosity_flags.h"

extern char** environ;

namespace lf {

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

// What the plot and the slopes use: relmse weighs every pixel by its own brightness, where RMSE
// is dominated by the few pixels on the light's edges (docs/convergence.md), and its square
// root falls as time^-1/2 for plain Monte Carlo.
double RelativeRmse(const ConvergenceRow& row) { return std::sqrt(row.error.relmse); }

}  // namespace

std::string EstimatedRelMseField(const ConvergenceRow& row) {
    return row.estimated_relmse ? absl::StrFormat("%.6e", *row.estimated_relmse) : "";
}

namespace {

std::string MethodTitle(const std::string& method) {
    return method == "path" ? "path tracing" : "radiosity";
}

// gnuplot draws the plot (a Debian package, deploy/install-deps.sh); the script stays next to
// the PNG so the figure can be restyled without rendering again.
absl::Status Plot(const ConvergenceResult& result, const std::string& script_path) {
    std::ofstream gp(script_path);
    gp << "set terminal pngcairo size 900,600 font 'sans,11'\n"
       << "set output " << GnuplotQuote(result.png_path) << "\n"
       << "set logscale xy\nset grid\nset key top right\n"
       << "set xlabel 'wall-clock seconds'\n"
       << "set ylabel 'relative RMSE, sqrt(relmse), against the reference'\n"
       << "set title 'Error against time'\n";
    std::string plot = "plot";
    for (const auto& [method, slope] : result.slopes) {
        gp << "$" << method << " << EOD\n";
        for (const ConvergenceRow& row : result.rows) {
            if (row.method == method) gp << row.seconds << " " << RelativeRmse(row) << "\n";
        }
        gp << "EOD\n";
        if (plot != "plot") plot += ",";
        plot += absl::StrFormat(" $%s using 1:2 with linespoints pt 7 title '%s (slope %.2f)'",
                                method, MethodTitle(method), slope);
    }
    gp << plot << "\n";
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
    csv << "method,budget,seconds,rmse,relmse,smape,estimated_relmse\n";
    for (const ConvergenceRow& row : result.rows) {
        csv << absl::StrFormat("%s,%d,%.4f,%.6e,%.6e,%.6e,%s\n", row.method, row.budget,
                               row.seconds, row.error.rmse, row.error.relmse, row.error.smape,
                               EstimatedRelMseField(row));
    }
    csv.close();
    if (!csv) return absl::PermissionDeniedError(result.csv_path + ": cannot write");
    return absl::OkStatus();
}

}  // namespace

absl::StatusOr<ConvergenceResult> RunConvergence(const ConvergenceOptions& options) {
    if (options.method != "path" && options.method != "radiosity" && options.method != "both") {
        return absl::InvalidArgumentError(
            absl::StrCat("--method ", options.method, ": expected path, radiosity or both"));
    }
    std::error_code ec;
    std::filesystem::create_directories(options.out_dir, ec);
    if (ec) return absl::PermissionDeniedError(options.out_dir + ": " + ec.message());

    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    if (options.resolution > 0) {
        CameraSpec& c = scene->camera;
        c.height = std::max(1, int(std::lround(double(c.height) * options.resolution / c.width)));
        c.width = options.resolution;
    }
    if (options.method != "path") {
        std::string why;
        absl::StatusOr<std::string> automatic = ChooseMethod(*scene, "auto", &why);
        if (!automatic.ok()) return automatic.status();
        if (*automatic != "radiosity") {
            return absl::InvalidArgumentError(absl::StrCat(
                "--method ", options.method, ": radiosity cannot model this scene: ", why));
        }
    }
    auto log = NamedLogger("converge");
    const std::string job_id = "converge-" + scene->content_hash.substr(0, 8);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    const PathTracer path_tracer(**embree, options.max_depth);

    auto render_path = [&](uint64_t spp, uint64_t seed) {
        RenderSettings settings;
        settings.spp = spp;
        settings.seed = seed;
        settings.threads = options.threads;
        settings.sampler = options.sampler;
        return RenderImage(camera, path_tracer, settings);
    };

    ConvergenceResult result;
    result.csv_path = (std::filesystem::path(options.out_dir) / "convergence.csv").string();
    result.png_path = (std::filesystem::path(options.out_dir) / "convergence.png").string();
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
        // Another seed, so the reference's noise is independent of the ladder's.
        log->info("job={} no reference given: path tracing one at {} spp", job_id,
                  options.reference_spp);
        absl::StatusOr<RenderOutput> out = render_path(options.reference_spp, options.seed + 1);
        if (!out.ok()) return out.status();
        reference = std::move(out->image);
        result.reference = absl::StrFormat(
            "no reference given: own path-traced reference, %d spp, seed %d, %.1f s",
            options.reference_spp, options.seed + 1, out->seconds);
    }
    if (absl::StatusOr<double> mse = EstimatedMse(reference); mse.ok()) {
        result.reference_rmse = std::sqrt(*mse);
    }

    auto add_row = [&](const std::string& method, int64_t budget, double seconds,
                       const Image& image) -> absl::Status {
        absl::StatusOr<ImageError> error = CompareImages(image, reference);
        if (!error.ok()) return error.status();
        // Path images estimate their own error from 2 spp on; a radiosity image's A/B halves
        // see only the display's sampling, not the solution's error.
        std::optional<double> estimated;
        if (method == "path" && budget >= 2) {
            if (absl::StatusOr<double> e = EstimatedRelMse(image); e.ok()) estimated = *e;
        }
        result.rows.push_back({method, budget, seconds, *error, estimated});
        log->info("job={} {} budget {}: {:.3f} s, rmse {:.4e}", job_id, method, budget, seconds,
                  error->rmse);
        return absl::OkStatus();
    };

    if (options.method != "radiosity") {
        for (uint64_t spp = 1; spp <= options.max_spp; spp *= 2) {
            absl::StatusOr<RenderOutput> out = render_path(spp, options.seed);
            if (!out.ok()) return out.status();
            if (absl::Status s = add_row("path", int64_t(spp), out->seconds, out->image); !s.ok()) {
                return s;
            }
        }
    }
    if (options.method != "path") {
        for (int64_t patches = options.min_patches; patches <= options.max_patches; patches *= 2) {
            const auto start = Clock::now();
            RadiositySettings solve;
            solve.patches = patches;
            solve.tolerance = options.radiosity_tolerance;
            absl::StatusOr<RadiosityOptions> ro = RadiosityOptionsOf(solve);
            if (!ro.ok()) return ro.status();
            ro->threads = options.threads;
            absl::StatusOr<std::unique_ptr<RadiosityRenderer>> radiosity =
                PrepareRadiosity(**embree, *ro);
            if (!radiosity.ok()) return radiosity.status();
            RenderSettings settings;
            settings.spp = options.radiosity_spp;
            settings.seed = options.seed;
            settings.threads = options.threads;
            settings.sampler = options.sampler;
            absl::StatusOr<RenderOutput> out = RenderImage(camera, **radiosity, settings);
            if (!out.ok()) return out.status();
            if (absl::Status s = add_row("radiosity", (*radiosity)->report().patches,
                                         SecondsSince(start), out->image);
                !s.ok()) {
                return s;
            }
        }
    }
    if (absl::Status s = WriteCsv(result); !s.ok()) return s;

    for (const std::string method : {"path", "radiosity"}) {
        std::vector<std::pair<double, double>> points;
        for (const ConvergenceRow& row : result.rows) {
            if (row.method == method) points.push_back({row.seconds, RelativeRmse(row)});
        }
        if (points.empty()) continue;
        absl::StatusOr<double> slope = LogLogSlope(points);
        if (!slope.ok()) {
            return absl::InvalidArgumentError(
                absl::StrCat(method, ": no slope from its ladder (", slope.status().message(),
                             "); widen it with --max-spp or --max-patches"));
        }
        result.slopes[method] = *slope;
    }
    const std::string script = (std::filesystem::path(options.out_dir) / "convergence.gp").string();
    if (absl::Status s = Plot(result, script); !s.ok()) return s;
    return result;
}

}  // namespace lf
