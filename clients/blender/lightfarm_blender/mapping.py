"""Blender's render settings to lightfarm's (docs/blender.md, "What transfers"). Pure: reads
attributes only, never imports bpy, so plain python3 tests it."""

from __future__ import annotations

import dataclasses
import os
import re
from typing import Any, Dict, List, Optional

# Cycles' default, for a scene whose Cycles settings are missing (the add-on disabled).
DEFAULT_SAMPLES = 16
_IMAGE_EXTENSIONS = (".exr", ".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".hdr", ".webp")


@dataclasses.dataclass(frozen=True)
class BlendRender:
    """What the add-on reads of a scene (read_render)."""
    resolution_x: int
    resolution_y: int
    resolution_percentage: int
    frame_start: int
    frame_end: int
    frame_step: int
    fps: int
    fps_base: float
    samples: int
    use_motion_blur: bool
    motion_blur_shutter: float
    filepath: str     # scene.render.filepath, "//" relative to the .blend
    blend_path: str   # bpy.data.filepath; "" for an unsaved file
    camera: str       # the active camera object's name; "" for none
    scene_name: str


def read_render(scene: Any, blend_path: str) -> BlendRender:
    """The settings of a bpy.types.Scene (or anything with its attributes)."""
    render = scene.render
    cycles = getattr(scene, "cycles", None)
    return BlendRender(
        resolution_x=render.resolution_x, resolution_y=render.resolution_y,
        resolution_percentage=render.resolution_percentage, frame_start=scene.frame_start,
        frame_end=scene.frame_end, frame_step=scene.frame_step, fps=render.fps,
        fps_base=render.fps_base,
        samples=cycles.samples if cycles is not None else DEFAULT_SAMPLES,
        use_motion_blur=render.use_motion_blur,
        motion_blur_shutter=render.motion_blur_shutter, filepath=render.filepath,
        blend_path=blend_path, camera=scene.camera.name if scene.camera else "",
        scene_name=scene.name)


def resolution(r: BlendRender) -> tuple:
    """The image size Blender renders: each side times the percentage, rounded down as Blender
    does (BKE_render_resolution), at least 1."""
    return (max(1, r.resolution_x * r.resolution_percentage // 100),
            max(1, r.resolution_y * r.resolution_percentage // 100))


def frames_text(r: BlendRender) -> str:
    """The frames Blender renders, frame_start to frame_end every frame_step: "A-B:STEP"."""
    if r.frame_end < r.frame_start:
        raise ValueError(f"scene {r.scene_name}: the frame range {r.frame_start}-{r.frame_end} "
                         "is reversed")
    text = f"{r.frame_start}-{r.frame_end}"
    return text + (f":{r.frame_step}" if r.frame_step != 1 else "")


def export_fps(r: BlendRender) -> float:
    """The frame rate of the exported animation: Blender's glTF exporter (3.4) writes frame f at
    f / render.fps seconds, ignoring fps_base, so lightfarm poses frame f at that time with this
    fps, and frame f is Blender's frame f (fps_base changes playback speed only)."""
    return float(r.fps)


def submit_settings(r: BlendRender) -> Dict[str, Any]:
    """lightfarm.Client.submit's keyword arguments for the scene: resolution, frames, fps, spp,
    shutter (frames the shutter stays open; 0 with motion blur off), camera and name."""
    if not r.camera:
        raise ValueError(f"scene {r.scene_name}: no active camera (set one in the Scene "
                         "properties)")
    name = os.path.basename(r.blend_path) or "untitled.blend"
    return dict(resolution=resolution(r), frames=frames_text(r), fps=export_fps(r),
                spp=max(1, int(r.samples)),
                shutter=float(r.motion_blur_shutter) if r.use_motion_blur else 0.0,
                camera=r.camera, name=f"{name} {r.scene_name}")


def output_pattern(r: BlendRender) -> str:
    """Where Fetch writes the frames, named as Blender names an OpenEXR frame
    (RenderSettings.frame_path): the output path made absolute ("//" is the .blend's folder),
    "####" appended when it has no '#' (a folder's frames are 0001.exr, ...), and .exr in place
    of an image extension or after the name. One run of '#' only: lightfarm numbers one."""
    path = r.filepath or "//"
    if path.startswith("//"):
        if not r.blend_path:
            raise ValueError(f"output path {path}: relative to the .blend, which is not saved "
                             "yet; save it first")
        path = os.path.join(os.path.dirname(r.blend_path), path[2:])
    folder, name = os.path.split(path)
    runs = re.findall("#+", name)
    if len(runs) > 1:
        raise ValueError(f"output path {r.filepath}: more than one run of '#'; lightfarm puts "
                         "the frame number in one")
    if not runs:
        name += "####"
    base, ext = os.path.splitext(name)
    if ext.lower() in _IMAGE_EXTENSIONS:
        name = base
    return os.path.join(os.path.normpath(folder), name + ".exr")


def cli_flags(settings: Dict[str, Any]) -> List[str]:
    """The `lightfarm render`/`submit` flags giving the same image as ``settings``
    (submit_settings without the name)."""
    width, height = settings["resolution"]
    flags = ["--resolution", f"{width}x{height}", "--frames", settings["frames"], "--fps",
             repr(settings["fps"]), "--spp", str(settings["spp"])]
    if settings["shutter"]:
        flags += ["--shutter", repr(settings["shutter"])]
    if settings.get("camera"):
        flags += ["--camera", settings["camera"]]
    return flags


def blend_relative(path: str, blend_path: str) -> Optional[str]:
    """A "//"-relative path (the panel's file settings) made absolute; "" stays None."""
    if not path:
        return None
    if path.startswith("//") and blend_path:
        return os.path.normpath(os.path.join(os.path.dirname(blend_path), path[2:]))
    return os.path.normpath(path)
