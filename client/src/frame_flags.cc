#include "lf/client/frame_flags.h"

#include "absl/strings/str_cat.h"

namespace lf {

void AddFrameFlags(CLI::App* cmd, FrameFlags& flags) {
    const std::string g = "Animation";
    cmd->add_option("--frames", flags.frames,
                    "render frames A to B (every STEP-th): frame f shows the scene at f / fps "
                    "seconds; -o and --png then need a run of # for the frame number "
                    "(out_####.exr)")
        ->type_name("A-B[:STEP]")
        ->group(g);
    cmd->add_option("--frame", flags.frame, "render frame N alone (the scene at N / fps seconds)")
        ->type_name("N")
        ->group(g);
    cmd->add_option_function<double>(
           "--fps",
           [&flags](double fps) {
               flags.fps = fps;
               flags.fps_given = true;
           },
           absl::StrCat("frames per second of --frames/--frame (default ", defaults::kFps, ")"))
        ->type_name("F")
        ->group(g);
}

absl::StatusOr<ShotSettings> ShotOfFrameFlags(const FrameFlags& flags) {
    ShotSettings shot;
    shot.fps = flags.fps;
    if (!flags.frames.empty() && !flags.frame.empty()) {
        return absl::InvalidArgumentError(absl::StrCat("--frame ", flags.frame, " with --frames ",
                                                       flags.frames,
                                                       ": give one frame or a range, not both"));
    }
    const std::string& text = flags.frames.empty() ? flags.frame : flags.frames;
    const char* flag = flags.frames.empty() ? "--frame" : "--frames";
    if (text.empty()) {
        if (flags.fps_given) {
            return absl::InvalidArgumentError(absl::StrCat(
                "--fps ", flags.fps, ": applies to --frames or --frame; a still has no time"));
        }
        return shot;
    }
    absl::StatusOr<FrameRange> range = ParseFrameRange(text);
    if (!range.ok())
        return absl::InvalidArgumentError(absl::StrCat(flag, ": ", range.status().message()));
    if (!flags.frame.empty() && range->count() != 1) {
        return absl::InvalidArgumentError(
            absl::StrCat("--frame ", flags.frame, ": expected one frame N; --frames takes ranges"));
    }
    shot.frames = *range;
    if (absl::Status s = CheckShotSettings(shot); !s.ok()) {
        return absl::InvalidArgumentError(absl::StrCat("--", s.message()));
    }
    return shot;
}

}  // namespace lf
