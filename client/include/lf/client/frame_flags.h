// --frames, --frame, --fps and --shutter: which frames of an animated scene `render` (and `submit`) make,
// and the time each shows. Without them the scene renders as a still.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "absl/status/statusor.h"
#include "lf/job/shot.h"

namespace lf {

struct FrameFlags {
    std::string frames;  // --frames A-B[:STEP]
    std::string frame;   // --frame N
    double fps = defaults::kFps;
    double shutter = 0;  // --shutter S: frames the shutter stays open
    bool frames_given = false, frame_given = false, fps_given = false;
};

void AddFrameFlags(CLI::App* cmd, FrameFlags& flags);

// The shot the flags ask for (frames nullopt: a still). InvalidArgument naming the flag for a
// malformed or empty range, --frame beside --frames, --fps or --shutter without either, or an
// fps or shutter out of range.
absl::StatusOr<ShotSettings> ShotOfFrameFlags(const FrameFlags& flags);

}  // namespace lf
