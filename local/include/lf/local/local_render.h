// `lightfarm render` without its flags and output: a scene file to an EXR (and PNG preview) in
// this process, by any method (path tracing, radiosity, Whitted, and the splatting methods light,
// bdpt, ppm), through the farm's planners and mergers (local_executor.h). The CLI prints the
// summary.
#pragma once

#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/false_color.h"
#include "lf/core/image_io.h"
#include "lf/core/scene_loader.h"
#include "lf/job/method_registry.h"
#include "lf/job/render_metadata.h"
#include "lf/job/settings.h"
#include "lf/job/shot.h"
#include "lf/job/splat_settings.h"
#include "lf/local/local_executor.h"

namespace lf {

// What the CLI shows of the sampling (its progress bar): Start when it starts, Update from any
// thread, Finish when it ends.
class RenderProgress {
  public:
    virtual ~RenderProgress() = default;
    virtual void Start() = 0;
    virtual void Update(size_t done, size_t total) = 0;
    virtual void Finish() = 0;
    // A shot (RunLocalShot): frame `frame`, the index-th of `count`, starts; `done` of `count`
    // are written.
    virtual void StartFrame(int index, int count, int frame) {}
    virtual void FinishFrame(int done, int count) {}
};

// Ctrl-C during a render. A signal handler sets `requested`; RunLocalRender sets `honoured`
// while it samples by a method that can stop with an unbiased partial image (the tile methods:
// path, whitted, radiosity's display, adaptive), so that a handler may exit at once otherwise.
// Lock-free atomics, safe in a signal handler.
struct RenderInterrupt {
    std::atomic<bool> requested{false};
    std::atomic<bool> honoured{false};
};

struct LocalRenderOptions {
    std::string scene_path;
    SceneOptions scene;    // --camera, --resolution, --filter
    std::string exr_path;  // empty: no EXR (-o out.png)
    std::string png_path;  // empty: no preview
    PngOptions preview;    // --exposure, --tonemap
    // --false-color: a false-colour PNG at false_color_path (a pattern for a shot, as exr_path).
    std::optional<FalseColorSpec> false_color;
    std::string false_color_path;
    std::optional<Method> method = FindMethod(defaults::kMethod);  // nullopt: auto (ChooseMethod)
    RenderSettings render;                                         // with --clamp and --aov
    AdaptiveSettings adaptive;  // used when a target error or a time limit is set
    int max_depth = defaults::kMaxDepth;
    RadiositySettings radiosity;
    PhotonSettings ppm;  // --photons, --ppm-radius, --ppm-alpha
    // Radiosity's files (RadiosityOptions): a solution to save or load, a PLY to export.
    std::string save_solution, load_solution, export_ply;
    RenderProgress* progress = nullptr;    // none when null
    RenderInterrupt* interrupt = nullptr;  // none when null
};

struct LocalRenderSummary {
    std::string job_id;
    Method method = Method::kPath;
    RenderStats stats;
    // Phases: loading the scene (and building its BVH), radiosity's whole preparation (meshing,
    // form factors, solve; its parts in `radiosity`), sampling the image; and the total.
    double load_seconds = 0, radiosity_seconds = 0, mesh_seconds = 0, render_seconds = 0;
    double seconds = 0;
    std::optional<RadiosityFigures> radiosity;
    int width = 0, height = 0;
    double estimated_error = -1;   // relative, from A/B; -1 below 2 samples per pixel
    double estimated_relmse = -1;  // EstimatedRelMse; -1 below 2 samples per pixel
    bool high_variance = false;
    bool adaptive = false;
    AdaptiveReport adaptive_report;
    // Interrupted: the files hold the passes done so far; `partial` says so, as the header does.
    std::string partial;
};

// Renders and writes the files; logs as the farm's jobs do (job=local-<scene hash>).
absl::StatusOr<LocalRenderSummary> RunLocalRender(const LocalRenderOptions& options);

// One frame of a shot: its files, and what posing the scene and building its BVH (and the
// method's kernel) took; bvh_seconds 0 when the frame reused the previous frame's.
struct LocalFrameSummary {
    int frame = 0;
    double time = 0;  // seconds: frame / fps
    double pose_seconds = 0, bvh_seconds = 0;
    std::string exr_path, png_path;
    LocalRenderSummary render;  // load_seconds: pose and BVH
};

struct LocalShotSummary {
    std::string job_id;
    bool moves = false;  // false: every frame rendered on the first frame's BVH and kernel
    std::vector<LocalFrameSummary> frames;  // those written, in order
    double seconds = 0;                     // the whole shot, loading included
    // Ctrl-C: the last frame written is partial and the shot stopped there.
    std::string partial;
};

// Ok when options.exr_path and options.png_path (patterns: out_####.exr) name every frame of
// `frames` (CheckFramePattern), naming -o or --png otherwise.
absl::Status CheckShotOutputs(const LocalRenderOptions& options, const FrameRange& frames);

// `render --frames`: loads the scene once, then for each frame of `shot.frames` poses it
// (PoseSceneAtFrame), rebuilds the BVH and the method's kernel when the animation moves
// anything (radiosity solves again: one instant per frame), and renders and writes the frame
// as RunLocalRender renders the still of FrameSpec (same bits; its header names the frame).
// options.exr_path and png_path are patterns (FramePath). An interrupt writes the current
// frame partial and ends the shot.
absl::StatusOr<LocalShotSummary> RunLocalShot(const LocalRenderOptions& options,
                                              const ShotSettings& shot);

}  // namespace lf
