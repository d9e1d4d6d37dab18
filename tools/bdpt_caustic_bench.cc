// BDPT against the path tracer where BDPT should win: the caustic the glass sphere of
// tests/scenes/materials.json throws on the floor, lit by the ceiling lamp (the scene's point
// light is removed: the path tracer cannot render its caustic, so its reference would lack it).
// Renders a long path-traced reference, then each method at its sample count, and prints wall
// seconds, RMSE (channel average) over the caustic region and over the image, and the RMSE each
// would reach in the other's time (MSE falls as 1 / time).
//
//   bdpt_caustic_bench [--resolution 64] [--reference-spp 8192] [--path-spp 256]
//                      [--bdpt-spp 64] [--max-depth 8]
//
// The caustic region: pixels whose centre ray first hits the floor within `--radius` of the
// point below the sphere, offset away from the lamp (where the lamp's light focuses).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/bdpt.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("BDPT vs path tracing RMSE on the glass sphere's caustic");
    int resolution = 64, max_depth = 8;
    uint64_t reference_spp = 8192, path_spp = 256, bdpt_spp = 64;
    double radius = 0.06;
    app.add_option("--resolution", resolution);
    app.add_option("--reference-spp", reference_spp);
    app.add_option("--path-spp", path_spp);
    app.add_option("--bdpt-spp", bdpt_spp);
    app.add_option("--max-depth", max_depth);
    app.add_option("--radius", radius, "of the caustic region on the floor");
    CLI11_PARSE(app, argc, argv);

    lf::SceneOptions options;
    options.width = options.height = resolution;
    auto scene =
        lf::LoadScene(std::string(LF_SOURCE_DIR) + "/tests/scenes/materials.json", options);
    if (!scene.ok()) {
        std::fprintf(stderr, "%s\n", std::string(scene.status().message()).c_str());
        return 1;
    }
    // The lamp's caustic only: the scene's point light throws one through the sphere too,
    // which the path-traced reference cannot render (a delta light seen through glass).
    scene->point_lights.clear();
    auto es = lf::EmbreeScene::Build(*scene);
    if (!es.ok()) return 1;
    const lf::Camera camera(scene->camera, (*es)->origin());
    const int w = camera.width(), h = camera.height();

    const auto path_image = [&](uint64_t spp, uint64_t seed, double* seconds) {
        const lf::PathTracer tracer(**es, max_depth);
        lf::RenderSettings settings;
        settings.spp = spp;
        settings.seed = seed;
        const auto start = std::chrono::steady_clock::now();
        lf::RenderOutput out = lf::RenderImage(camera, tracer, settings).value();
        *seconds = Seconds(start);
        std::vector<double> v(size_t(w * h));
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) v[size_t(y * w + x)] = out.image.Pixel(x, y).Average();
        }
        return v;
    };
    const auto bdpt_image = [&](uint64_t spp, double* seconds) {
        lf::FrameRenderSettings settings;
        settings.max_depth = max_depth;
        settings.seed = 5;
        const lf::BdptRenderer renderer(**es, camera, settings);
        const lf::PixelRect rect{0, 0, w, h};
        lf::TileSums sums(rect);
        lf::SplatList splats(w, h);
        const auto start = std::chrono::steady_clock::now();
        renderer.Render(lf::FrameWork{rect, 0, spp, 0, 0}, sums, splats);
        lf::TileSums splat_tile(rect);
        splats.AddTo(splat_tile);
        *seconds = Seconds(start);
        std::vector<double> v(size_t(w * h));
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const lf::PixelSums& s = splat_tile.at(x, y);
                double splat = 0;
                for (int c = 0; c < 3; ++c) splat += s.sum[0][c].Value() + s.sum[1][c].Value();
                v[size_t(y * w + x)] = sums.at(x, y).Mean().Average() + splat / 3 / double(spp);
            }
        }
        return v;
    };

    // The caustic region (render space: the scene's origin subtracted).
    const lf::Vec3 lamp = lf::Vec3(lf::Vec3d(0.278, 0.5488, 0.28) - (*es)->origin());
    const lf::Vec3 ball = lf::Vec3(lf::Vec3d(0.17, 0.09, 0.16) - (*es)->origin());
    const lf::Vec3 d = Normalize(ball - lamp);
    const lf::Vec3 focus = ball + d * ((ball.y - lf::Vec3(-(*es)->origin()).y) / -d.y);
    std::vector<bool> caustic(size_t(w * h), false);
    int region = 0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const auto hit = (*es)->Intersect(camera.GenerateRay(x, y, 0.5f, 0.5f));
            if (hit && Length(hit->p - focus) < radius && std::abs(hit->n.y) > 0.9f) {
                caustic[size_t(y * w + x)] = true;
                ++region;
            }
        }
    }

    double t_ref = 0, t_path = 0, t_bdpt = 0;
    const std::vector<double> ref = path_image(reference_spp, 99, &t_ref);
    const std::vector<double> path = path_image(path_spp, 1, &t_path);
    const std::vector<double> bdpt = bdpt_image(bdpt_spp, &t_bdpt);
    const auto rmse = [&](const std::vector<double>& v, bool only_caustic) {
        double sum = 0;
        int n = 0;
        for (size_t i = 0; i < v.size(); ++i) {
            if (only_caustic && !caustic[i]) continue;
            sum += (v[i] - ref[i]) * (v[i] - ref[i]);
            ++n;
        }
        return std::sqrt(sum / std::max(n, 1));
    };
    std::printf("reference: path %llu spp, %.1f s; caustic region %d pixels\n",
                (unsigned long long)reference_spp, t_ref, region);
    std::printf("%-5s %6s %8s %14s %12s %22s\n", "method", "spp", "seconds", "caustic RMSE",
                "image RMSE", "caustic RMSE in path's time");
    std::printf("%-5s %6llu %8.2f %14.5f %12.5f %22.5f\n", "path", (unsigned long long)path_spp,
                t_path, rmse(path, true), rmse(path, false), rmse(path, true));
    std::printf("%-5s %6llu %8.2f %14.5f %12.5f %22.5f\n", "bdpt", (unsigned long long)bdpt_spp,
                t_bdpt, rmse(bdpt, true), rmse(bdpt, false),
                rmse(bdpt, true) * std::sqrt(t_bdpt / t_path));
    return 0;
}
