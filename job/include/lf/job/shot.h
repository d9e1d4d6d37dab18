// A shot: the frames of an animated scene one job renders, the time each frame shows, the
// shutter and the file names of per-frame outputs. Local mode (`render --frames`) and the farm
// (`submit --frames`) read the same settings, so frame f is the same image either way: the scene
// posed at f / fps seconds (Blender's exporter writes frame f of its timeline at that time),
// rendered as a still with the job's seed (the noise pattern stays put from frame to frame, as
// Cycles' default does).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/job/task_status.h"

namespace lf {

// Frames first, first + step, ... up to last (inclusive).
struct FrameRange {
    int first = 1, last = 1, step = 1;

    int count() const { return (last - first) / step + 1; }
    int at(int i) const { return first + i * step; }
    // Whether `frame` is one of the range's; its position in it through IndexOf.
    bool Contains(int frame) const;
    int IndexOf(int frame) const { return (frame - first) / step; }
    friend bool operator==(const FrameRange&, const FrameRange&) = default;
};

inline constexpr int kMaxFrameNumber = 1'000'000;  // |frame| at most this
// Frames in one job: each frame's merger holds its tile file open while the shot runs, and the
// job's record lists every frame (a longer sequence is several shots, as studios split them).
inline constexpr int kMaxShotFrames = 10'000;
// Tasks a shot may plan over all its frames (lf::ShotExecution::Make): a task costs the
// coordinator a few hundred bytes while the shot runs.
inline constexpr int64_t kMaxShotTasks = 1'000'000;
// Frame times stay finite and distinct: |frame| / fps at most 10^9 seconds.
inline constexpr double kMinFps = 1e-3, kMaxFps = 1000;
inline constexpr double kMaxShutter = 10;  // frames
inline constexpr int kMaxChunk = 1000;

namespace defaults {
inline constexpr double kFps = 24;
}

struct ShotSettings {
    // nullopt: a still, the scene as its files pose it (no animation is evaluated). One frame
    // ({N, N, 1}: `--frame N`) is the scene at N / fps.
    std::optional<FrameRange> frames;
    double fps = defaults::kFps;
    // Frames the shutter stays open, centred on the frame's time; 0: the instant.
    double shutter = 0;
    // Whole frames per farm task (Flamenco's chunk size); 1: each frame planned as a still.
    int chunk = 1;
};

// A shot's frame as the coordinator reports and records it (JobRecord::frames).
struct FrameProgress {
    int frame = 0;
    int tasks_done = 0, tasks_total = 0;
    bool done = false;        // every task merged
    std::string result_path;  // its EXR once the coordinator wrote it; "" before
    TaskTimes times;          // summed over its merged tasks (a chunk's parts count their own)
    friend bool operator==(const FrameProgress&, const FrameProgress&) = default;
};

// "A-B", "A-B:STEP" or "N" (one frame); frames may be negative ("-10--1"). InvalidArgument
// naming the text for anything else, an empty or reversed range, a step below 1, a frame beyond
// ±kMaxFrameNumber or more than kMaxShotFrames frames.
absl::StatusOr<FrameRange> ParseFrameRange(std::string_view text);
// The text ParseFrameRange reads back: "1-24", "1-24:2", "7".
std::string FrameRangeText(const FrameRange& range);

// Ok when the settings are within their limits (the frames as ParseFrameRange checks them, fps in
// [kMinFps, kMaxFps], shutter in [0, kMaxShutter], chunk in 1..kMaxChunk); otherwise
// InvalidArgument naming the field, as CheckJobSettings reports the others.
absl::Status CheckShotSettings(const ShotSettings& shot);

// Seconds of frame `frame`: frame / fps.
double FrameSeconds(int frame, double fps);
// The shutter interval of `frame` in seconds: open and close, equal for shutter 0.
struct ShutterInterval {
    double open = 0, close = 0;
};
ShutterInterval ShutterOf(int frame, const ShotSettings& shot);

// Poses `scene` (as loaded, or posed at another frame before) at frame `frame`'s time, the one
// way local mode and the workers move a scene to a frame. A scene without animation stays as it
// is; malformed animation data is the loader's Scene::animation_error, returned with the frame
// named, as is a pose PoseAt refuses.
absl::Status PoseSceneAtFrame(int frame, const ShotSettings& shot, Scene& scene);

// The file of frame `frame` from `pattern`: its one run of '#' becomes the frame number,
// zero-padded to as many digits as there are '#' (Blender's convention; a negative frame keeps
// its sign before the digits). A pattern without '#' names itself.
std::string FramePath(std::string_view pattern, int frame);
// Ok when `pattern` (the value of `flag`) can name every frame of `frames`: at most one run of
// '#', and one unless there is a single frame. InvalidArgument naming the flag otherwise.
absl::Status CheckFramePattern(std::string_view flag, std::string_view pattern,
                               const FrameRange& frames);

}  // namespace lf
