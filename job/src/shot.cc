#include "lf/job/shot.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "absl/strings/str_cat.h"
#include "lf/core/scene_animation.h"

namespace lf {

namespace {

// Reads an integer (with an optional '-') from the front of `text`, advancing it.
bool ReadInt(std::string_view& text, int& value) {
    const char* end = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (ec != std::errc() || ptr == text.data()) return false;
    text.remove_prefix(size_t(ptr - text.data()));
    return true;
}

absl::Status CheckRange(const FrameRange& range, std::string_view what) {
    if (range.step < 1) {
        return absl::InvalidArgumentError(absl::StrCat("frames \"", std::string(what),
                                                       "\": the step ", range.step, " is below 1"));
    }
    for (int frame : {range.first, range.last}) {
        if (std::abs(int64_t(frame)) > kMaxFrameNumber) {
            return absl::InvalidArgumentError(absl::StrCat("frames \"", std::string(what),
                                                           "\": frame ", frame, " is beyond ±",
                                                           kMaxFrameNumber));
        }
    }
    if (range.last < range.first) {
        return absl::InvalidArgumentError(
            absl::StrCat("frames \"", std::string(what), "\": the range is reversed (", range.last,
                         " before ", range.first, "); write FIRST-LAST with FIRST <= LAST"));
    }
    if ((int64_t(range.last) - range.first) / range.step + 1 > kMaxShotFrames) {
        return absl::InvalidArgumentError(absl::StrCat("frames \"", std::string(what),
                                                       "\": more than ", kMaxShotFrames,
                                                       " frames in one job; split the shot"));
    }
    return absl::OkStatus();
}

}  // namespace

bool FrameRange::Contains(int frame) const {
    return frame >= first && frame <= last && (frame - first) % step == 0;
}

absl::StatusOr<FrameRange> ParseFrameRange(std::string_view text) {
    const auto malformed = [&] {
        return absl::InvalidArgumentError(
            absl::StrCat("frames \"", std::string(text),
                         "\": expected FIRST-LAST, FIRST-LAST:STEP or one frame N (e.g. 1-240, "
                         "1-240:2, 12)"));
    };
    if (text.empty()) {
        return absl::InvalidArgumentError("frames \"\": the range is empty; expected FIRST-LAST");
    }
    std::string_view rest = text;
    FrameRange range;
    if (!ReadInt(rest, range.first)) return malformed();
    range.last = range.first;
    if (!rest.empty() && rest.front() == '-') {
        rest.remove_prefix(1);
        if (!ReadInt(rest, range.last)) return malformed();
        if (!rest.empty() && rest.front() == ':') {
            rest.remove_prefix(1);
            if (!ReadInt(rest, range.step)) return malformed();
        }
    }
    if (!rest.empty()) return malformed();
    if (absl::Status s = CheckRange(range, text); !s.ok()) return s;
    return range;
}

std::string FrameRangeText(const FrameRange& range) {
    if (range.first == range.last) return absl::StrCat(range.first);
    std::string text = absl::StrCat(range.first, "-", range.last);
    if (range.step != 1) absl::StrAppend(&text, ":", range.step);
    return text;
}

absl::Status CheckShotSettings(const ShotSettings& shot) {
    if (shot.frames) {
        if (absl::Status s = CheckRange(*shot.frames, FrameRangeText(*shot.frames)); !s.ok()) {
            return s;
        }
    }
    if (!(shot.fps >= kMinFps && shot.fps <= kMaxFps)) {
        return absl::InvalidArgumentError(
            absl::StrCat("fps ", shot.fps, ": expected ", kMinFps, " to ", kMaxFps));
    }
    if (!(shot.shutter >= 0 && shot.shutter <= kMaxShutter)) {
        return absl::InvalidArgumentError(absl::StrCat(
            "shutter ", shot.shutter, ": expected 0 (the instant) to ", kMaxShutter, " frames"));
    }
    if (shot.chunk < 1 || shot.chunk > kMaxChunk) {
        return absl::InvalidArgumentError(
            absl::StrCat("chunk ", shot.chunk, ": expected 1 to ", kMaxChunk, " frames a task"));
    }
    if (shot.shutter > 0 && !shot.frames) {
        return absl::InvalidArgumentError(
            "shutter: motion blur needs a frame (--frame N or --frames A-B): a still shows the "
            "scene as its files pose it, at no time");
    }
    return absl::OkStatus();
}

double FrameSeconds(int frame, double fps) { return double(frame) / fps; }

ShutterInterval ShutterOf(int frame, const ShotSettings& shot) {
    const double centre = FrameSeconds(frame, shot.fps);
    const double half = 0.5 * shot.shutter / shot.fps;
    return {centre - half, centre + half};
}

absl::Status PoseSceneAtFrame(int frame, const ShotSettings& shot, Scene& scene) {
    const double seconds = FrameSeconds(frame, shot.fps);
    absl::Status s = scene.animation_error;
    if (s.ok() && scene.animation) s = scene.animation->PoseAt(seconds, scene);
    if (s.ok()) return s;
    return absl::Status(s.code(), absl::StrCat("frame ", frame, " (", seconds, " s) of ",
                                               scene.source, ": ", s.message()));
}

std::string FramePath(std::string_view pattern, int frame) {
    const size_t begin = pattern.find('#');
    if (begin == std::string_view::npos) return std::string(pattern);
    size_t end = begin;
    while (end < pattern.size() && pattern[end] == '#') ++end;
    std::string digits = std::to_string(std::abs(int64_t(frame)));
    if (digits.size() < end - begin) digits.insert(0, end - begin - digits.size(), '0');
    return absl::StrCat(std::string(pattern.substr(0, begin)), frame < 0 ? "-" : "", digits,
                        std::string(pattern.substr(end)));
}

absl::Status CheckFramePattern(std::string_view flag, std::string_view pattern,
                               const FrameRange& frames) {
    const size_t begin = pattern.find('#');
    if (begin == std::string_view::npos) {
        if (frames.count() == 1) return absl::OkStatus();
        return absl::InvalidArgumentError(absl::StrCat(
            std::string(flag), " \"", std::string(pattern), "\" has no '#' to number ",
            frames.count(), " frames (", FrameRangeText(frames), "); write e.g. out_####.exr"));
    }
    const size_t end = pattern.find_first_not_of('#', begin);
    if (end != std::string_view::npos && pattern.find('#', end) != std::string_view::npos) {
        return absl::InvalidArgumentError(
            absl::StrCat(std::string(flag), " \"", std::string(pattern),
                         "\" has more than one run of '#'; the frame number goes in one"));
    }
    return absl::OkStatus();
}

}  // namespace lf
