#include "lf/client/bench.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <numbers>

#include "lf/core/camera.h"
#include "lf/core/plural.h"
#include "lf/core/sampler.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/local/local_executor.h"
#include "lf/local/method_factory.h"

namespace lf {

namespace {

// Closest-hit rays from uniform points in the scene bounds in uniform directions: the
// incoherent rays a path tracer casts, without any shading.
double RawRaysPerSecond(const EmbreeScene& scene, uint64_t count, int threads) {
    const auto [lo_d, hi_d] = scene.scene().Bounds();
    const Vec3 lo(lo_d - scene.origin()), extent(hi_d - lo_d);
    std::atomic<uint64_t> hits{0};
    tbb::task_arena arena(threads);
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, 4096),
                          [&](const tbb::blocked_range<uint64_t>& r) {
                              uint64_t local_hits = 0;
                              for (uint64_t i = r.begin(); i != r.end(); ++i) {
                                  Sampler s(7, 0, 0, i);
                                  const Vec2 a = s.Get2D(), b = s.Get2D();
                                  const Vec3 o(lo.x + a.x * extent.x, lo.y + a.y * extent.y,
                                               lo.z + b.x * extent.z);
                                  const float z = 1 - 2 * b.y,
                                              phi = 2 * std::numbers::pi_v<float> * s.Get1D();
                                  const float rr = std::sqrt(std::max(0.0f, 1 - z * z));
                                  const Ray ray{o, Vec3(rr * std::cos(phi), rr * std::sin(phi), z)};
                                  local_hits += scene.Intersect(ray).has_value();
                              }
                              hits += local_hits;
                          });
    });
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return double(count) / seconds;
}

}  // namespace

absl::Status RunBench(const BenchOptions& options) {
    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    if (!scene.ok()) return scene.status();
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    absl::StatusOr<std::unique_ptr<RadianceEstimator>> tracer =
        MakeRayTracer(Method::kPath, **embree, options.max_depth, options.light_strategy);
    if (!tracer.ok()) return tracer.status();

    RenderSettings settings;
    settings.spp = options.spp;
    settings.threads = options.threads;
    settings.sampler = options.sampler;
    absl::StatusOr<RenderOutput> rendered = RenderImage(camera, **tracer, settings);
    if (!rendered.ok()) return rendered.status();
    const RenderOutput& out = *rendered;
    const double raw = RawRaysPerSecond(**embree, options.raw_rays, options.threads);

    const double sps = double(out.stats.samples) / out.seconds;
    const double rps = double(out.stats.rays) / out.seconds;
    std::printf(
        "scene            %s (%dx%d, %llu spp, max depth %s, %s, %s sampler, %s light "
        "sampling)\n",
        options.scene_path.c_str(), camera.width(), camera.height(),
        (unsigned long long)options.spp,
        options.max_depth < 0 ? "unlimited" : std::to_string(options.max_depth).c_str(),
        Plural(options.threads, "thread").c_str(), SamplerTypeName(options.sampler),
        LightStrategyName(options.light_strategy));
    std::printf("path tracing     %.3f M samples/s, %.3f M rays/s, %.2f rays/sample, %.2f s\n",
                sps * 1e-6, rps * 1e-6, double(out.stats.rays) / double(out.stats.samples),
                out.seconds);
    std::printf("embree raw       %.3f M closest-hit rays/s (incoherent)\n", raw * 1e-6);
    std::printf("ray efficiency   %.1f%% of the raw rate\n", 100.0 * rps / raw);
    return absl::OkStatus();
}

}  // namespace lf
