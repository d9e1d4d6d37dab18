// Radiosity cost and accuracy against mesh size: for each patch count, form-factor and solve
// time, form-factor storage, peak memory, iterations, and optionally the difference from a
// path-traced reference image. The numbers in docs/radiosity.md come from here.
//
//   radiosity_bench [--scene S] [--patches 1000,4000,16000] [--reference-spp 1024]
//                   [--target-error 0.2,0.1]  (refine from each patch count to each target)
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/local_executor.h"

namespace {

// Peak resident set size (VmHWM) in MiB; reset between runs where the kernel allows.
double PeakRssMiB() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024;
    }
    return -1;
}

void ResetPeakRss() { std::ofstream("/proc/self/clear_refs") << "5"; }

double CpuSeconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
           1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// sqrt(Σ (a - b)^2 / Σ b^2) over R, G, B.
double RelativeRms(const lf::Image& a, const lf::Image& b, const char* prefix_a = "",
                   const char* prefix_b = "") {
    double diff = 0, norm = 0;
    for (const char* c : {"R", "G", "B"}) {
        const auto& va = *a.FindChannel(std::string(prefix_a) + c);
        const auto& vb = *b.FindChannel(std::string(prefix_b) + c);
        for (size_t i = 0; i < va.size(); ++i) {
            diff += (double(va[i]) - vb[i]) * (double(va[i]) - vb[i]);
            norm += double(vb[i]) * vb[i];
        }
    }
    return std::sqrt(diff / norm);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("Radiosity cost and accuracy against mesh size");
    std::string scene_path = std::string(LF_SOURCE_DIR) + "/tests/scenes/cornell_box.json";
    std::vector<int64_t> patch_counts = {1000, 4000, 16000};
    std::vector<double> targets;
    std::string solver_name = "gauss-seidel";
    uint64_t reference_spp = 0;
    int resolution = 64;
    int threads = 0;
    app.add_option("--scene", scene_path, "scene file");
    app.add_option("--patches", patch_counts, "patch counts")->delimiter(',');
    app.add_option("--solver", solver_name, "jacobi, gauss-seidel or shooting");
    app.add_option("--reference-spp", reference_spp,
                   "compare with a path-traced image at this many samples per pixel (0: skip)");
    app.add_option("--resolution", resolution, "image size for the comparison");
    app.add_option("--threads", threads, "0: all cores");
    app.add_option("--target-error", targets,
                   "refine from each patch count to each of these targets (0: uniform)")
        ->delimiter(',');
    CLI11_PARSE(app, argc, argv);

    auto solver = lf::ParseRadiositySolver(solver_name);
    auto scene = lf::LoadScene(scene_path);
    if (!solver.ok() || !scene.ok()) {
        std::fprintf(stderr, "%s\n",
                     (solver.ok() ? scene.status() : solver.status()).ToString().c_str());
        return 1;
    }
    scene->camera.width = scene->camera.height = resolution;
    auto embree = lf::EmbreeScene::Build(*scene);
    if (!embree.ok()) {
        std::fprintf(stderr, "%s\n", embree.status().ToString().c_str());
        return 1;
    }
    const lf::Camera camera(scene->camera, (*embree)->origin());
    lf::RenderSettings settings;
    settings.spp = std::max<uint64_t>(reference_spp, 1);
    settings.threads = threads;
    lf::Image reference;
    if (reference_spp > 0) {
        reference = lf::RenderImage(camera, lf::PathTracer(**embree, -1), settings).value().image;
        std::printf("path-traced reference: %d x %d at %lu spp, noise (A-B)/2 relative rms %.4f\n",
                    resolution, resolution, reference_spp,
                    RelativeRms(reference, reference, "A.", "B.") / 2);
    }

    if (targets.empty()) targets = {0};
    std::printf("%8s %6s %7s %7s %8s %8s %8s %8s %10s %9s %9s %6s %7s %9s %9s %8s\n", "patches",
                "target", "passes", "sides", "wall s", "ff s", "cpu s", "solve s", "nonzeros",
                "ff MiB", "peak MiB", "iters", "sweeps", "residual", "rays", "vs path");
    for (int64_t n : patch_counts) {
        for (double target : targets) {
            ResetPeakRss();
            lf::RadiosityOptions options;
            options.patches = n;
            options.solver = *solver;
            options.threads = threads;
            options.target_error = target;
            const double cpu_start = CpuSeconds();
            const auto start = std::chrono::steady_clock::now();
            auto renderer = lf::PrepareRadiosity(**embree, options);
            const double wall =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const double cpu = CpuSeconds() - cpu_start;
            if (!renderer.ok()) {
                std::fprintf(stderr, "%s\n", renderer.status().ToString().c_str());
                return 1;
            }
            const lf::RadiosityReport& r = (*renderer)->report();
            const double peak = PeakRssMiB();
            double difference = NAN;
            if (reference_spp > 0) {
                difference = RelativeRms(
                    lf::RenderImage(camera, **renderer, settings).value().image, reference);
            }
            std::printf(
                "%8ld %6.3g %7zu %7ld %8.2f %8.2f %8.2f %8.2f %10ld %9.1f %9.1f %6d %7.1f %9.2e "
                "%9ld %8.4f\n",
                r.patches, target, r.refinement.size(), r.sides, wall, r.form_factor_seconds, cpu,
                r.solve_seconds, r.nonzero_form_factors, double(r.form_factor_bytes) / (1 << 20),
                peak, r.iterations, r.sweeps, r.residual, r.visibility_rays, difference);
            for (size_t pass = 0; pass < r.refinement.size(); ++pass) {
                const lf::RadiosityRefinementPass& q = r.refinement[pass];
                std::printf(
                    "    pass %zu: %ld patches, form factors %.3f s, %ld rays, %ld pairs "
                    "evaluated, %ld reused, %ld cells split\n",
                    pass + 1, q.patches, q.form_factor_seconds, q.visibility_rays, q.pairs,
                    q.reused_pairs, q.split);
            }
            std::fflush(stdout);
        }
    }
    return 0;
}
