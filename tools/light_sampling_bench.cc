// Light-sampling error of the two light strategies (LightStrategy::kPower: picks by power, area
// sampling; kBvh: light BVH, spherical rectangles and triangles, sphere cones) against a
// high-sample reference (rendered with kBvh; both strategies are unbiased), on the repository's
// scenes (--scene, any number) and on synthetic ones: many small emitters at different distances
// (--emitters) and a big lamp close to a wall (--lamp). By default the light reflected once
// (emitters seen directly left out); --bounces -1 for full paths.
//
// Each strategy renders --repeat times with different seeds, alternating power and bvh so that
// both see the same machine load; per sample count it prints the CPU seconds (summed), the relative
// RMSE, and the three ratios bvh / power: variance at equal spp, time at equal spp, and RMSE at
// equal time, sqrt(var ratio * time ratio), since the MSE falls as 1 / samples.
//
//   light_sampling_bench [--scene a.json --scene b.gltf] [--emitters 1000] [--lamp]
//                        [--spp 4,16,64] [--reference-spp 1024] [--bounces 1]
//                        [--sampler sobol] [--repeat 3] [--resolution 64] [--threads 0]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/sampler.h"
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

// A 4 x 3 wall with a floor, lit by a 1 x 1 lamp 0.15 in front of the wall and facing it: the
// wall near the lamp sees it under nearly a hemisphere, where area sampling's 1 / r^2 and
// cosines vary most. The camera looks at the wall past the lamp's dark back.
lf::Scene NearLamp(int resolution) {
    lf::Scene scene;
    lf::Material white;
    white.reflectance = lf::Rgb(0.7f);
    lf::Material glow;
    glow.reflectance = lf::Rgb(0.0f);
    glow.emission = lf::Rgb(4.0f, 3.5f, 3.0f);
    scene.materials = {white, glow};
    lf::TriangleMesh room;
    room.positions = {{-2, -1, 0}, {2, -1, 0},  {2, 2, 0},  {-2, 2, 0},   // wall, facing +z
                      {-2, -1, 0}, {-2, -1, 3}, {2, -1, 3}, {2, -1, 0}};  // floor, facing +y
    room.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    scene.meshes.push_back(room);
    lf::TriangleMesh lamp;
    lamp.material = 1;
    lamp.positions = {{-0.5, 0, 0.15}, {-0.5, 1, 0.15}, {0.5, 1, 0.15}, {0.5, 0, 0.15}};
    lamp.triangles = {{0, 1, 2}, {0, 2, 3}};  // facing -z, towards the wall
    scene.meshes.push_back(lamp);
    scene.camera.position = {1.2, 0.8, 3};
    scene.camera.look_at = {0, 0.5, 0};
    scene.camera.up = {0, 1, 0};
    scene.camera.fov_y_deg = 60;
    scene.camera.width = scene.camera.height = resolution;
    return scene;
}

struct Options {
    std::vector<uint64_t> spps = {4, 16, 64};
    uint64_t reference_spp = 1024;
    int bounces = 1;
    int threads = 0;
    int repeat = 3;
    lf::SamplerType sampler = lf::defaults::kSampler;
};

// The process's CPU time: unlike wall time it does not count the time other processes on a
// shared machine take from this one.
double CpuSeconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

lf::Image RenderDepth(const lf::EmbreeScene& es, const lf::Camera& camera,
                      lf::LightStrategy strategy, int max_depth, uint64_t spp, uint64_t seed,
                      const Options& o, double* seconds) {
    const lf::PathTracer tracer(es, max_depth, strategy);
    lf::RenderSettings settings;
    settings.spp = spp;
    settings.seed = seed;
    settings.threads = o.threads;
    settings.sampler = o.sampler;
    const double start = CpuSeconds();
    lf::Image image = lf::RenderImage(camera, tracer, settings).value().image;
    *seconds = CpuSeconds() - start;
    return image;
}

// The light reflected from what each pixel sees, R, G, B per pixel: a render of o.bounces
// bounces minus a render of emission alone from the same camera samples (same seed), so that
// emitters seen directly, whose edges alias alike under either strategy, do not swamp the
// comparison. `seconds`: the first render's CPU time (building the tracer included, as a job
// would pay it).
struct Reflected {
    std::vector<double> rgb;
    double seconds = 0;
};

Reflected Render(const lf::EmbreeScene& es, const lf::Camera& camera, lf::LightStrategy strategy,
                 uint64_t spp, uint64_t seed, const Options& o) {
    Reflected reflected;
    double emission_seconds = 0;
    const lf::Image bounce =
        RenderDepth(es, camera, strategy, o.bounces, spp, seed, o, &reflected.seconds);
    const lf::Image emission =
        RenderDepth(es, camera, strategy, 0, spp, seed, o, &emission_seconds);
    for (const char* c : {"R", "G", "B"}) {
        const std::vector<float>& a = *bounce.FindChannel(c);
        const std::vector<float>& b = *emission.FindChannel(c);
        for (size_t i = 0; i < a.size(); ++i) reflected.rgb.push_back(double(a[i]) - b[i]);
    }
    return reflected;
}

// Mean of (a - b)^2 over the mean of b squared: the relative MSE.
double RelativeMse(const std::vector<double>& a, const std::vector<double>& b) {
    double squared = 0, sum = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        squared += (a[i] - b[i]) * (a[i] - b[i]);
        sum += b[i];
    }
    const double mean = sum / double(a.size());
    return squared / double(a.size()) / (mean * mean);
}

int Bench(const std::string& name, const lf::Scene& scene, const Options& o) {
    auto es = lf::EmbreeScene::Build(scene);
    if (!es.ok()) {
        std::fprintf(stderr, "%s: %s\n", name.c_str(), es.status().ToString().c_str());
        return 1;
    }
    const lf::Camera camera(scene.camera, (*es)->origin());
    const Reflected reference =
        Render(**es, camera, lf::LightStrategy::kBvh, o.reference_spp, 12345, o);
    std::printf("%s: %d x %d, %s, bounces %d, reference %lu spp (bvh) in %.2f s\n", name.c_str(),
                scene.camera.width, scene.camera.height, lf::SamplerTypeName(o.sampler), o.bounces,
                o.reference_spp, reference.seconds);
    std::printf("  %6s %9s %9s %10s %10s %9s %9s %11s\n", "spp", "s power", "s bvh", "rRMSE pow",
                "rRMSE bvh", "var b/p", "time b/p", "eqtime b/p");
    for (uint64_t spp : o.spps) {
        double seconds[2] = {0, 0}, mse[2] = {0, 0};
        for (int r = 0; r < o.repeat; ++r) {
            // Alternate which goes first, so neither always runs on a warmer or quieter machine.
            for (int k = 0; k < 2; ++k) {
                const int s = (k + r) % 2;  // 0: power, 1: bvh
                const Reflected image = Render(
                    **es, camera, s == 0 ? lf::LightStrategy::kPower : lf::LightStrategy::kBvh, spp,
                    uint64_t(1 + r), o);
                seconds[s] += image.seconds;
                mse[s] += RelativeMse(image.rgb, reference.rgb) / o.repeat;
            }
        }
        const double var_ratio = mse[1] / mse[0], time_ratio = seconds[1] / seconds[0];
        std::printf("  %6lu %9.3f %9.3f %10.4f %10.4f %9.3f %9.3f %11.3f\n", spp, seconds[0],
                    seconds[1], std::sqrt(mse[0]), std::sqrt(mse[1]), var_ratio, time_ratio,
                    std::sqrt(var_ratio * time_ratio));
        std::fflush(stdout);
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("Light-sampling RMSE of the power and light-BVH light strategies");
    std::vector<std::string> scenes;
    int emitters = 0;
    bool lamp = false;
    int resolution = 64;
    std::string sampler = lf::SamplerTypeName(lf::defaults::kSampler);
    Options o;
    app.add_option("--scene", scenes, "scene files (json, glTF) to measure");
    app.add_option("--emitters", emitters, "also a scene of this many small emitters (0: none)")
        ->check(CLI::Range(0, 1000000));
    app.add_flag("--lamp", lamp, "also a big lamp close to a wall");
    app.add_option("--spp", o.spps, "sample counts to compare")->delimiter(',');
    app.add_option("--reference-spp", o.reference_spp, "samples per pixel of the reference")
        ->check(CLI::PositiveNumber);
    app.add_option("--bounces", o.bounces, "1: direct light; -1: full paths")
        ->check(CLI::Range(-1, 1000));
    app.add_option("--sampler", sampler, "sobol or independent");
    app.add_option("--repeat", o.repeat, "renders per strategy and sample count")
        ->check(CLI::Range(1, 1000));
    app.add_option("--resolution", resolution, "image size")->check(CLI::Range(1, 4096));
    app.add_option("--threads", o.threads, "0: all cores");
    CLI11_PARSE(app, argc, argv);
    const std::optional<lf::SamplerType> type = lf::SamplerTypeFromName(sampler);
    if (!type) {
        std::fprintf(stderr, "--sampler: unknown sampler '%s'\n", sampler.c_str());
        return 1;
    }
    o.sampler = *type;
    if (scenes.empty() && emitters == 0 && !lamp) {
        scenes.push_back(std::string(LF_SOURCE_DIR) + "/tests/scenes/cornell_box.json");
        emitters = 1000;
    }

    for (const std::string& path : scenes) {
        auto scene = lf::LoadScene(path);
        if (!scene.ok()) {
            std::fprintf(stderr, "%s\n", scene.status().ToString().c_str());
            return 1;
        }
        scene->camera.width = scene->camera.height = resolution;
        if (Bench(path.substr(path.find_last_of('/') + 1), *scene, o) != 0) return 1;
    }
    if (lamp && Bench("lamp near a wall", NearLamp(resolution), o) != 0) return 1;
    if (emitters > 0 &&
        Bench(std::to_string(emitters) + " emitters", ManyEmitters(emitters, resolution), o) != 0) {
        return 1;
    }
    return 0;
}
