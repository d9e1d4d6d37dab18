// How honest the image's own relMSE estimate (lf::EstimatedRelMse, from its A/B halves) is:
// for each spp of a ladder, the estimate over the true relMSE against a high-spp reference, the
// reference's own noise taken out, summed over seeds. Also the same numerator over the
// reference's value ("oracle"), which separates the numerator's honesty from the denominator's.
// The tables of docs/convergence.md "Error estimates and plan predictions" come from here.
//
//   error_estimate_bench SCENE [--resolution 64] [--reference-spp 8192] [--max-spp 1024]
//                        [--sampler sobol|independent] [--seeds 4] [--threads 0]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace {

const std::vector<float>& Channel(const lf::Image& image, const std::string& name) {
    return *image.FindChannel(name);
}

struct Truth {
    double relmse = 0;  // mean (x - r)^2 / (r^2 + eps) less the reference's own variance
    double oracle = 0;  // mean ((A - B) / 2)^2 / (r^2 + eps)
};

Truth Measure(const lf::Image& image, const lf::Image& reference) {
    Truth t;
    size_t n = 0;
    for (const std::string c : {"R", "G", "B"}) {
        const auto &x = Channel(image, c), &a = Channel(image, "A." + c),
                   &b = Channel(image, "B." + c);
        const auto &r = Channel(reference, c), &ra = Channel(reference, "A." + c),
                   &rb = Channel(reference, "B." + c);
        for (size_t i = 0; i < x.size(); ++i) {
            const double d = double(x[i]) - r[i], half = 0.5 * (double(a[i]) - b[i]);
            const double ref_half = 0.5 * (double(ra[i]) - rb[i]);
            const double denominator = double(r[i]) * r[i] + lf::kRelativeErrorEpsilon;
            t.relmse += (d * d - ref_half * ref_half) / denominator;
            t.oracle += half * half / denominator;
            ++n;
        }
    }
    t.relmse /= double(n);
    t.oracle /= double(n);
    return t;
}

int Fail(const absl::Status& status) {
    std::fprintf(stderr, "error_estimate_bench: %s\n", std::string(status.message()).c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("Estimated against true relMSE over a ladder of spp");
    std::string scene_path, sampler_name = "sobol";
    int resolution = 64, seeds = 4, threads = 0;
    uint64_t reference_spp = 8192, max_spp = 1024;
    app.add_option("scene", scene_path, "scene file")->required()->check(CLI::ExistingFile);
    app.add_option("--resolution", resolution, "image width; the height keeps the aspect")
        ->check(CLI::Range(2, 4096));
    app.add_option("--reference-spp", reference_spp)->check(CLI::Range(2, 1 << 20));
    app.add_option("--max-spp", max_spp, "ladder 2, 4, ... up to this")
        ->check(CLI::Range(2, 1 << 20));
    app.add_option("--sampler", sampler_name)->check(CLI::IsMember({"sobol", "independent"}));
    app.add_option("--seeds", seeds, "images per rung, each with its own seed")
        ->check(CLI::Range(1, 1000));
    app.add_option("--threads", threads)->check(CLI::Range(0, 1024));
    CLI11_PARSE(app, argc, argv);

    absl::StatusOr<lf::Scene> scene = lf::LoadScene(scene_path);
    if (!scene.ok()) return Fail(scene.status());
    const double aspect = double(scene->camera.height) / scene->camera.width;
    scene->camera.width = resolution;
    scene->camera.height = std::max(1, int(std::lround(resolution * aspect)));
    absl::StatusOr<std::unique_ptr<lf::EmbreeScene>> embree = lf::EmbreeScene::Build(*scene);
    if (!embree.ok()) return Fail(embree.status());
    const lf::Camera camera(scene->camera, (*embree)->origin());
    const lf::PathTracer tracer(**embree, -1);
    lf::RenderSettings settings;
    settings.threads = threads;
    settings.sampler =
        sampler_name == "sobol" ? lf::SamplerType::kSobol : lf::SamplerType::kIndependent;
    settings.spp = reference_spp;
    settings.seed = 1000;  // apart from the ladder's seeds 1, 2, ...
    absl::StatusOr<lf::RenderOutput> reference = lf::RenderImage(camera, tracer, settings);
    if (!reference.ok()) return Fail(reference.status());
    std::printf("%s at %dx%d, %s sampler, reference %llu spp (%.1f s), %d seeds\n",
                scene_path.c_str(), camera.width(), camera.height(), sampler_name.c_str(),
                (unsigned long long)reference_spp, reference->seconds, seeds);
    std::printf("%6s %11s %11s %11s %9s %9s %9s\n", "spp", "true", "estimated", "oracle/true",
                "est/true", "min", "max");
    for (uint64_t spp = 2; spp <= max_spp; spp *= 2) {
        double truth = 0, estimated = 0, oracle = 0, lo = INFINITY, hi = 0;
        for (int s = 1; s <= seeds; ++s) {
            settings.spp = spp;
            settings.seed = uint64_t(s);
            absl::StatusOr<lf::RenderOutput> out = lf::RenderImage(camera, tracer, settings);
            if (!out.ok()) return Fail(out.status());
            absl::StatusOr<double> estimate = lf::EstimatedRelMse(out->image);
            if (!estimate.ok()) return Fail(estimate.status());
            const Truth t = Measure(out->image, reference->image);
            truth += t.relmse;
            estimated += *estimate;
            oracle += t.oracle;
            lo = std::min(lo, *estimate / t.relmse);
            hi = std::max(hi, *estimate / t.relmse);
        }
        std::printf("%6llu %11.4g %11.4g %11.4g %9.2f %9.2f %9.2f\n", (unsigned long long)spp,
                    truth / seeds, estimated / seeds, oracle / truth, estimated / truth, lo, hi);
    }
    return 0;
}
