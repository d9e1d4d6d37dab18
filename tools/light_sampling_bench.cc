// Direct-lighting error (light reflected once, emitters seen directly left out; --bounces -1 for
// full paths) of the two light
// strategies (LightStrategy::kPower: picks by power, area sampling; kBvh: light BVH, spherical
// triangles, sphere cones) on the Cornell box and on a scene with many small emitters at
// different distances, against a high-sample reference
// (rendered with kBvh; both strategies are unbiased). For each strategy and sample count: the
// wall time, the RMSE relative to the reference's mean, and that RMSE scaled to the power
// strategy's time at the same spp (RMSE * sqrt(t / t_power)): the equal-time comparison, since
// RMSE falls as 1 / sqrt(samples).
//
//   light_sampling_bench [--emitters 1000] [--spp 4,16,64] [--reference-spp 1024]
//                        [--bounces 1] [--resolution 64] [--threads 0]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace {

// A 40 x 40 floor under `count` small emitting triangles (0.1 across, facing down) at distances
// from 0.5 to 30 (log-uniform), all of one radiance; the camera looks down at the
// floor's centre, where the near lights make sharp highlights and the far ones a faint wash.
lf::Scene ManyEmitters(int count, int resolution) {
    lf::Scene scene;
    lf::Material floor;
    floor.reflectance = lf::Rgb(0.5f);
    lf::Material glow;
    glow.reflectance = lf::Rgb(0.0f);
    glow.emission = lf::Rgb(20.0f, 12.0f, 6.0f);
    scene.materials = {floor, glow};
    lf::TriangleMesh plane;
    const double s = 20;
    plane.positions = {{-s, 0, -s}, {-s, 0, s}, {s, 0, s}, {s, 0, -s}};
    plane.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(plane);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int i = 0; i < count; ++i) {
        const double distance = 0.5 * std::pow(60.0, unit(rng));
        const double phi = 2 * std::numbers::pi * unit(rng), cos_t = 0.1 + 0.9 * unit(rng);
        const double sin_t = std::sqrt(1 - cos_t * cos_t);
        const lf::Vec3d c(distance * sin_t * std::cos(phi), distance * cos_t,
                          distance * sin_t * std::sin(phi));
        lf::TriangleMesh light;
        light.material = 1;
        light.positions = {c, c + lf::Vec3d(0.1, 0, 0), c + lf::Vec3d(0, 0, 0.1)};  // faces down
        light.triangles = {{0, 1, 2}};
        scene.meshes.push_back(light);
    }
    scene.camera.position = {0, 0.15, -2};
    scene.camera.look_at = {0, 0, 0};
    scene.camera.up = {0, 1, 0};
    scene.camera.fov_y_deg = 60;
    scene.camera.width = scene.camera.height = resolution;
    return scene;
}

// The light reflected from what each pixel sees, R, G, B per pixel: a render of `bounces` bounces
// minus a render of emission alone from the same camera samples (same seed), so that emitters
// seen directly, whose edges alias alike under either strategy, do not swamp the comparison.
// `seconds`: the first render's wall time.
struct DirectLight {
    std::vector<double> rgb;
    double seconds = 0;
};

lf::Image RenderDepth(const lf::EmbreeScene& es, const lf::Camera& camera,
                      lf::LightStrategy strategy, int max_depth, uint64_t spp, uint64_t seed,
                      int threads, double* seconds) {
    const lf::PathTracer tracer(es, max_depth, strategy);
    lf::RenderSettings settings;
    settings.spp = spp;
    settings.seed = seed;
    settings.threads = threads;
    const auto start = std::chrono::steady_clock::now();
    lf::Image image = lf::RenderImage(camera, tracer, settings).value().image;
    *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return image;
}

DirectLight Render(const lf::EmbreeScene& es, const lf::Camera& camera, lf::LightStrategy strategy,
                   int bounces, uint64_t spp, uint64_t seed, int threads) {
    DirectLight direct;
    double emission_seconds = 0;
    const lf::Image bounce =
        RenderDepth(es, camera, strategy, bounces, spp, seed, threads, &direct.seconds);
    const lf::Image emission =
        RenderDepth(es, camera, strategy, 0, spp, seed, threads, &emission_seconds);
    for (const char* c : {"R", "G", "B"}) {
        const std::vector<float>& a = *bounce.FindChannel(c);
        const std::vector<float>& b = *emission.FindChannel(c);
        for (size_t i = 0; i < a.size(); ++i) direct.rgb.push_back(double(a[i]) - b[i]);
    }
    return direct;
}

// sqrt(mean of (a - b)^2) / mean of b.
double RelativeRmse(const std::vector<double>& a, const std::vector<double>& b) {
    double squared = 0, sum = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        squared += (a[i] - b[i]) * (a[i] - b[i]);
        sum += b[i];
    }
    return std::sqrt(squared / double(a.size())) / (sum / double(a.size()));
}

struct Options {
    std::vector<uint64_t> spps = {4, 16, 64};
    uint64_t reference_spp = 1024;
    int bounces = 1;
    int threads = 0;
};

int Bench(const std::string& name, const lf::Scene& scene, const Options& o) {
    auto es = lf::EmbreeScene::Build(scene);
    if (!es.ok()) {
        std::fprintf(stderr, "%s: %s\n", name.c_str(), es.status().ToString().c_str());
        return 1;
    }
    const lf::Camera camera(scene.camera, (*es)->origin());
    const DirectLight reference =
        Render(**es, camera, lf::LightStrategy::kBvh, o.bounces, o.reference_spp, 12345, o.threads);
    std::printf("%s: %d x %d, reference %lu spp (kBvh) in %.2f s\n", name.c_str(),
                scene.camera.width, scene.camera.height, o.reference_spp, reference.seconds);
    std::printf("  %6s %8s %9s %9s %14s\n", "spp", "strategy", "seconds", "rel RMSE",
                "RMSE@t(power)");
    for (uint64_t spp : o.spps) {
        const DirectLight power =
            Render(**es, camera, lf::LightStrategy::kPower, o.bounces, spp, 1, o.threads);
        const DirectLight bvh =
            Render(**es, camera, lf::LightStrategy::kBvh, o.bounces, spp, 1, o.threads);
        const double e_power = RelativeRmse(power.rgb, reference.rgb);
        const double e_bvh = RelativeRmse(bvh.rgb, reference.rgb);
        std::printf("  %6lu %8s %9.3f %9.4f %14.4f\n", spp, "power", power.seconds, e_power,
                    e_power);
        std::printf("  %6lu %8s %9.3f %9.4f %14.4f   (bvh / power at equal time: %.2f)\n", spp,
                    "bvh", bvh.seconds, e_bvh, e_bvh * std::sqrt(bvh.seconds / power.seconds),
                    e_bvh * std::sqrt(bvh.seconds / power.seconds) / e_power);
        std::fflush(stdout);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("Direct-lighting RMSE of the power and light-BVH light strategies");
    std::string cornell = std::string(LF_SOURCE_DIR) + "/tests/scenes/cornell_box.json";
    int emitters = 1000;
    int resolution = 64;
    Options o;
    app.add_option("--cornell", cornell, "Cornell box scene file");
    app.add_option("--emitters", emitters, "small emitters in the many-lights scene")
        ->check(CLI::Range(1, 1000000));
    app.add_option("--spp", o.spps, "sample counts to compare")->delimiter(',');
    app.add_option("--reference-spp", o.reference_spp, "samples per pixel of the reference")
        ->check(CLI::PositiveNumber);
    app.add_option("--bounces", o.bounces, "1: direct light; -1: full paths")
        ->check(CLI::Range(-1, 1000));
    app.add_option("--resolution", resolution, "image size")->check(CLI::Range(1, 4096));
    app.add_option("--threads", o.threads, "0: all cores");
    CLI11_PARSE(app, argc, argv);

    auto box = lf::LoadScene(cornell);
    if (!box.ok()) {
        std::fprintf(stderr, "%s\n", box.status().ToString().c_str());
        return 1;
    }
    box->camera.width = box->camera.height = resolution;
    if (Bench("cornell box", *box, o) != 0) return 1;
    return Bench(std::to_string(emitters) + " emitters", ManyEmitters(emitters, resolution), o);
}
