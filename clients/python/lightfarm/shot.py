"""A shot's frames as the CLI reads them (lf/job/shot.h): "A-B", "A-B:STEP" or "N", and the
per-frame file names of a pattern's run of '#' (out_####.exr -> out_0012.exr)."""

from __future__ import annotations

import dataclasses
import re
from typing import Iterator, Optional

from .errors import InvalidArgument

# The farm's limits (lf/job/shot.h).
MAX_FRAME_NUMBER = 1_000_000
MAX_SHOT_FRAMES = 10_000
MIN_FPS, MAX_FPS = 1e-3, 1000.0
MAX_SHUTTER = 10.0  # frames
MAX_CHUNK = 1000
DEFAULT_FPS = 24.0

_RANGE = re.compile(r"(-?\d+)(?:-(-?\d+)(?::(-?\d+))?)?")


@dataclasses.dataclass(frozen=True)
class FrameRange:
    """Frames first, first + step, ... up to last (inclusive)."""
    first: int
    last: int
    step: int = 1

    def __iter__(self) -> Iterator[int]:
        return iter(range(self.first, self.last + 1, self.step))

    def __len__(self) -> int:
        return (self.last - self.first) // self.step + 1

    def __contains__(self, frame: object) -> bool:
        return (isinstance(frame, int) and self.first <= frame <= self.last
                and (frame - self.first) % self.step == 0)

    def __str__(self) -> str:
        if self.first == self.last:
            return str(self.first)
        return f"{self.first}-{self.last}" + (f":{self.step}" if self.step != 1 else "")


def parse_frames(text: str) -> FrameRange:
    """"A-B", "A-B:STEP" or "N" (frames may be negative: "-10--1"); InvalidArgument naming the
    text for anything else, an empty or reversed range, a step below 1, a frame beyond
    ±MAX_FRAME_NUMBER or more than MAX_SHOT_FRAMES frames."""
    m = _RANGE.fullmatch(text)
    if not text:
        raise InvalidArgument('frames "": the range is empty; expected FIRST-LAST')
    if not m:
        raise InvalidArgument(f'frames "{text}": expected FIRST-LAST, FIRST-LAST:STEP or one '
                              "frame N (e.g. 1-240, 1-240:2, 12)")
    first = int(m.group(1))
    last = int(m.group(2)) if m.group(2) is not None else first
    step = int(m.group(3)) if m.group(3) is not None else 1
    return check_range(FrameRange(first, last, step), text)


def check_range(frames: FrameRange, what: Optional[str] = None) -> FrameRange:
    """``frames`` when within the farm's limits; InvalidArgument otherwise."""
    what = str(frames) if what is None else what
    if frames.step < 1:
        raise InvalidArgument(f'frames "{what}": the step {frames.step} is below 1')
    for frame in (frames.first, frames.last):
        if abs(frame) > MAX_FRAME_NUMBER:
            raise InvalidArgument(f'frames "{what}": frame {frame} is beyond ±{MAX_FRAME_NUMBER}')
    if frames.last < frames.first:
        raise InvalidArgument(f'frames "{what}": the range is reversed ({frames.last} before '
                              f"{frames.first}); write FIRST-LAST with FIRST <= LAST")
    if len(frames) > MAX_SHOT_FRAMES:
        raise InvalidArgument(f'frames "{what}": more than {MAX_SHOT_FRAMES} frames in one job; '
                              "split the shot")
    return frames


def frame_path(pattern: str, frame: int) -> str:
    """``pattern`` with its run of '#' replaced by ``frame``, zero-padded to as many digits as
    there are '#' (Blender's convention; a negative frame keeps its sign before the digits). A
    pattern without '#' names itself."""
    begin = pattern.find("#")
    if begin < 0:
        return pattern
    end = begin
    while end < len(pattern) and pattern[end] == "#":
        end += 1
    digits = str(abs(frame)).rjust(end - begin, "0")
    return pattern[:begin] + ("-" if frame < 0 else "") + digits + pattern[end:]


def check_frame_pattern(what: str, pattern: str, frames: FrameRange) -> None:
    """InvalidArgument unless ``pattern`` (the value of ``what``) can name every frame: one run
    of '#', or none for a single frame."""
    begin = pattern.find("#")
    if begin < 0:
        if len(frames) == 1:
            return
        raise InvalidArgument(f'{what} "{pattern}" has no \'#\' to number {len(frames)} frames '
                              f"({frames}); write e.g. out_####.exr")
    end = begin
    while end < len(pattern) and pattern[end] == "#":
        end += 1
    if "#" in pattern[end:]:
        raise InvalidArgument(f'{what} "{pattern}" has more than one run of \'#\'; the frame '
                              "number goes in one")
