"""Check, Submit to lightfarm and Fetch: the work runs on background threads (farm_jobs); a
timer copies their status into scene.lightfarm for the panel."""

import os
import tempfile
from typing import Dict, Optional, Tuple

import bpy

from . import farm_jobs, mapping, scene_check

# The running or last task of each scene: (scene name, "submit" | "fetch").
_tasks: Dict[Tuple[str, str], farm_jobs.FarmTask] = {}
POLL_SECONDS = 0.5


def task(scene, what: str) -> Optional[farm_jobs.FarmTask]:
    """The scene's last "submit" or "fetch" task (the headless test joins it)."""
    return _tasks.get((scene.name, what))


def sync(scene) -> bool:
    """Copies the scene's tasks' status into scene.lightfarm; True while one still runs."""
    s = scene.lightfarm
    running = False
    for what in ("submit", "fetch"):
        t = task(scene, what)
        if t is None:
            continue
        status = t.status
        if status.get("job_id") and s.job_id != status["job_id"]:
            s.job_id = status["job_id"]
        if "fraction" in status:
            s.progress = status["fraction"]
        s.status = status["error"] or status["message"]
        running = running or not status["done"]
    return running


def _poll() -> Optional[float]:
    running = False
    for scene in bpy.data.scenes:
        running = sync(scene) or running
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "PROPERTIES":
                area.tag_redraw()
    return POLL_SECONDS if running else None


def _start_polling() -> None:
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=POLL_SECONDS)


def _connection(scene) -> farm_jobs.Connection:
    s = scene.lightfarm
    blend = bpy.data.filepath
    return farm_jobs.Connection(s.server.strip(), mapping.blend_relative(s.token_file, blend),
                                mapping.blend_relative(s.tls_ca, blend))


def _busy(scene, what: str) -> bool:
    t = task(scene, what)
    return t is not None and not t.status["done"]


def check_scene(scene) -> list:
    """Lists what does not transfer in scene.lightfarm.issues and returns it."""
    issues = scene_check.scene_issues(scene)
    s = scene.lightfarm
    s.issues.clear()
    for text in issues:
        s.issues.add().text = text
    return issues


def export_gltf(path: str) -> None:
    """The active scene as a .glb by Blender's glTF exporter: renderable objects with modifiers
    applied, cameras, punctual lights and animations over the frame range, with frame f at
    f / fps seconds (never slid to 0, on versions that could)."""
    options = dict(filepath=path, export_format="GLB", use_active_scene=True,
                   use_renderable=True, export_apply=True, export_cameras=True,
                   export_lights=True, export_animations=True, export_frame_range=True,
                   export_yup=True)
    known = bpy.ops.export_scene.gltf.get_rna_type().properties.keys()
    if "export_anim_slide_to_zero" in known:
        options["export_anim_slide_to_zero"] = False
    result = bpy.ops.export_scene.gltf(**options)
    if "FINISHED" not in result or not os.path.isfile(path):
        raise RuntimeError(f"the glTF export to {path} failed")


class LIGHTFARM_OT_check(bpy.types.Operator):
    """List what of this scene does not transfer to lightfarm"""
    bl_idname = "lightfarm.check"
    bl_label = "Check scene"

    def execute(self, context):
        issues = check_scene(context.scene)
        self.report({"WARNING"} if issues else {"INFO"},
                    f"lightfarm: {len(issues)} things do not transfer" if issues
                    else "lightfarm: everything transfers")
        return {"FINISHED"}


class LIGHTFARM_OT_submit(bpy.types.Operator):
    """Export the scene with the glTF exporter and render its frames on the farm"""
    bl_idname = "lightfarm.submit"
    bl_label = "Submit to lightfarm"

    def execute(self, context):
        scene = context.scene
        s = scene.lightfarm
        if _busy(scene, "submit"):
            self.report({"ERROR"}, "lightfarm: this scene's submission is still uploading or "
                                   "watching its job")
            return {"CANCELLED"}
        issues = check_scene(scene)
        blend = bpy.data.filepath
        render = mapping.read_render(scene, blend)
        try:
            settings = mapping.submit_settings(render)
            pattern = mapping.output_pattern(render)
        except ValueError as e:
            self.report({"ERROR"}, f"lightfarm: {e}")
            return {"CANCELLED"}
        keep = mapping.blend_relative(s.export_dir, blend)
        folder = keep or tempfile.mkdtemp(prefix="lightfarm-blender-")
        stem = os.path.splitext(os.path.basename(blend))[0] or "untitled"
        glb = os.path.join(folder, f"{stem}_{scene.name}.glb")
        try:
            os.makedirs(folder, exist_ok=True)
            export_gltf(glb)
        except (OSError, RuntimeError) as e:
            self.report({"ERROR"}, f"lightfarm: {e}")
            return {"CANCELLED"}
        s.job_id = ""
        s.progress = 0
        s.output_pattern = pattern
        s.status = "submitting…"
        _tasks[scene.name, "submit"] = farm_jobs.submit(_connection(scene), glb, settings,
                                                        None if keep else folder)
        _start_polling()
        print(f"lightfarm: {scene.name}: lightfarm submit {glb} "
              + " ".join(mapping.cli_flags(settings)))
        self.report({"WARNING"} if issues else {"INFO"},
                    f"lightfarm: submitting frames {settings['frames']}"
                    + (f"; {len(issues)} things do not transfer (see the panel)" if issues else ""))
        return {"FINISHED"}


class LIGHTFARM_OT_fetch(bpy.types.Operator):
    """Write the job's finished frames as an image sequence at the output path (OpenEXR)"""
    bl_idname = "lightfarm.fetch"
    bl_label = "Fetch frames"

    @classmethod
    def poll(cls, context):
        return bool(context.scene.lightfarm.job_id)

    def execute(self, context):
        scene = context.scene
        s = scene.lightfarm
        if _busy(scene, "fetch"):
            self.report({"ERROR"}, "lightfarm: a fetch is still running")
            return {"CANCELLED"}
        _tasks[scene.name, "fetch"] = farm_jobs.fetch(_connection(scene), s.job_id,
                                                      s.output_pattern)
        _start_polling()
        self.report({"INFO"}, f"lightfarm: fetching job {s.job_id} to {s.output_pattern}")
        return {"FINISHED"}


_CLASSES = (LIGHTFARM_OT_check, LIGHTFARM_OT_submit, LIGHTFARM_OT_fetch)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
