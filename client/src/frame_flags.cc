#include "lf/client/frame_flags.h"

#include "absl/strings/str_cat.h"

namespace lf {

void AddFrameFlags(CLI::App* cmd, FrameFlags& flags) {
    const std::string g = "Animation";
    // Functions, not plain options, so that an empty value counts as given.
    cmd->add_option_function<std::string>(
           "--frames",
           [&flags](const std::string& text) {
               flags.frames = text;
               flags.frames_given = true;
           },
           "render frames A to B (every STEP-th): frame f shows the scene at f / fps seconds; -o "
           "and --png then need a run of # for the frame number (out_####.exr)")
        ->type_name("A-B[:STEP]")
        ->group(g);
    cmd->add_option_function<std::string>(
           "--frame",
           [&flags](const std::string& text) {
               flags.frame = text;
               flags.frame_given = true;
           },
           "render frame N alone (the scene at N / fps seconds)")
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
    cmd->add_option("--shutter", flags.shutter,
                    absl::StrCat("motion blur: the shutter stays open S frames, centred on each "
                                 "frame's time (Blender's default); each camera sample draws a "
                                 "time in it. 0 (the default): the instant. Up to ",
                                 kMaxShutter, "; radiosity refuses it"))
        ->type_name("S")
        ->group(g);
}

absl::StatusOr<ShotSettings> ShotOfFrameFlags(const FrameFlags& flags) {
    ShotSettings shot;
    shot.fps = flags.fps;
    shot.shutter = flags.shutter;
    if (flags.frames_given && flags.frame_given) {
        return absl::InvalidArgumentError(absl::StrCat("--frame ", flags.frame, " with --frames ",
                                                       flags.frames,
                                                       ": give one frame or a range, not both"));
    }
    const std::string& text = flags.frames_given ? flags.frames : flags.frame;
    const char* flag = flags.frames_given ? "--frames" : "--frame";
    if (!flags.frames_given && !flags.frame_given) {
        if (flags.fps_given) {
            return absl::InvalidArgumentError(absl::StrCat(
                "--fps ", flags.fps, ": applies to --frames or --frame; a still has no time"));
        }
        if (flags.shutter != 0) {
            return absl::InvalidArgumentError(
                absl::StrCat("--shutter ", flags.shutter,
                             ": motion blur needs --frames or --frame; a still has no time"));
        }
        return shot;
    }
    absl::StatusOr<FrameRange> range = ParseFrameRange(text);
    if (!range.ok())
        return absl::InvalidArgumentError(absl::StrCat(flag, ": ", range.status().message()));
    if (flags.frame_given && range->count() != 1) {
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
