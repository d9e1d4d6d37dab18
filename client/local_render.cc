#include "local_render.h"

#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/version.h"
#include "progress_bar.h"

namespace lf {

ExrAttributes DescribeRender(const std::string& scene_hash, const std::string& method,
                             const RenderSettings& settings, int max_depth,
                             const RenderOutput& output) {
    return {
        {"lightfarm.version", std::string(kVersion)},
        {"lightfarm.sceneHash", scene_hash},
        {"lightfarm.method", method},
        {"lightfarm.spp", int(settings.spp)},
        {"lightfarm.seed", std::to_string(settings.seed)},
        {"lightfarm.maxDepth", max_depth},
        {"lightfarm.seconds", output.seconds},
        {"lightfarm.invalidSamples", std::to_string(output.stats.invalid_samples)},
        {"lightfarm.rays", std::to_string(output.stats.rays)},
        {"lightfarm.channels",
         std::string("R,G,B: mean radiance W m^-2 sr^-1 (box filter); A.*, B.*: means of the "
                     "even and odd samples; spp: samples per pixel")},
    };
}

namespace {

// Fails before any rendering, so an hour of work is not lost to a typo in the output path.
absl::Status CheckWritable(const std::string& path) {
    if (path.empty()) return absl::OkStatus();
    const bool existed = std::filesystem::exists(path);
    std::ofstream probe(path, std::ios::app);
    if (!probe) {
        return absl::PermissionDeniedError(path + ": cannot write here: " + std::strerror(errno));
    }
    probe.close();
    if (!existed) std::filesystem::remove(path);
    return absl::OkStatus();
}

}  // namespace

absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options) {
    for (const std::string* path : {&options.exr_path, &options.png_path}) {
        if (absl::Status s = CheckWritable(*path); !s.ok()) return s;
    }
    auto log = spdlog::get("render");
    if (!log) log = spdlog::default_logger()->clone("render");

    absl::StatusOr<Scene> scene = LoadScene(options.scene_path);
    if (!scene.ok()) return scene.status();
    const std::string job_id = "local-" + scene->content_hash.substr(0, 8);

    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    if (!embree.ok()) return embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    const PathTracer tracer(**embree, options.max_depth);
    log->info("job={} rendering {} ({}x{}, {} spp, seed {}, max depth {}, tile {})", job_id,
              options.scene_path, camera.width(), camera.height(), options.render.spp,
              options.render.seed, options.max_depth < 0 ? "unlimited" : std::to_string(options.max_depth),
              options.render.tile);

    ProgressBar bar("render");
    const RenderOutput out = RenderImage(camera, tracer, options.render, [&](size_t done, size_t n) {
        if (options.progress) bar.Update(done, n);
    });
    if (options.progress) bar.Finish();
    if (out.stats.invalid_samples > 0) {
        log->warn("job={} {} NaN or infinite samples were discarded (counted as zero)", job_id,
                  out.stats.invalid_samples);
    }

    const ExrAttributes attributes =
        DescribeRender(scene->content_hash, "path", options.render, options.max_depth, out);
    if (absl::Status s = WriteExr(options.exr_path, out.image, attributes); !s.ok()) return s;
    if (!options.png_path.empty()) {
        if (absl::Status s = WritePng(options.png_path, out.image); !s.ok()) return s;
    }
    return LocalRenderSummary{job_id, out.stats, out.seconds, camera.width(), camera.height()};
}

}  // namespace lf
