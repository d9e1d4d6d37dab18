"""Run inside Blender by blender_addon_test.py:

    blender -b --factory-startup --python-exit-code 1 --python addon_script.py -- \
        --zip lightfarm_blender.zip --server HOST:PORT --dir DIR

Installs and enables the add-on from the build's zip, builds a small animated scene, saves it
as DIR/scene.blend, submits it with the add-on's operator (token file and export folder
relative to the .blend), waits for the job, fetches the frames, and writes DIR/result.json for
the driver. Any failed check raises, and Blender exits 1.
"""

import argparse
import json
import math
import os
import struct
import sys

import bpy

parser = argparse.ArgumentParser()
parser.add_argument("--zip", required=True)
parser.add_argument("--server", required=True)
parser.add_argument("--dir", required=True)
args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:])

# The add-on, from the zip the build made.
bpy.ops.preferences.addon_install(filepath=args.zip, overwrite=True)
bpy.ops.preferences.addon_enable(module="lightfarm_blender")
import lightfarm_blender  # noqa: E402
from lightfarm_blender import operators  # noqa: E402

assert "lib" in os.path.dirname(sys.modules["lightfarm"].__file__), "the zip's client"

# The scene: factory startup's cube, light and camera, a ground plane, a moving sphere.
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.samples = 4
scene.render.resolution_x, scene.render.resolution_y = 64, 48
scene.render.resolution_percentage = 50  # 32 x 24
scene.frame_start, scene.frame_end, scene.frame_step = 2, 6, 2  # frames 2, 4, 6
scene.render.fps, scene.render.fps_base = 24, 1.001  # the exporter ignores fps_base
scene.render.use_motion_blur = True
scene.render.motion_blur_shutter = 0.5
scene.render.filepath = "//frames/shot_"  # no '#': Blender appends the frame's 4 digits
scene.render.image_settings.file_format = "OPEN_EXR"
bpy.data.objects["Light"].data.shadow_soft_size = 0
bpy.data.objects["Light"].data.energy = 2000
bpy.ops.mesh.primitive_plane_add(size=12, location=(0, 0, -1))
plane = bpy.context.object
plane.modifiers.new("emitter", "PARTICLE_SYSTEM")  # does not transfer: listed
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(-2, 1, 0), segments=16,
                                     ring_count=8)
sphere = bpy.context.object
sphere.keyframe_insert("location", frame=2)
sphere.location = (2, 1, 0.5)
sphere.keyframe_insert("location", frame=6)
bpy.ops.object.light_add(type="AREA", location=(0, 0, 4))  # dropped by the exporter: listed
camera = bpy.data.objects["Camera"]
scene.camera = camera
scene.frame_set(2)

os.makedirs(args.dir, exist_ok=True)
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(args.dir, "scene.blend"))
s = scene.lightfarm
s.server = args.server
s.token_file = "//alice.token"
s.export_dir = "//export"

from lightfarm_blender import panel  # noqa: E402

summary = panel._summary(scene)
assert summary == "32x24, frames 2-6:2 at 24 fps, 4 spp, shutter 0.5 frames", summary
assert bpy.ops.lightfarm.check() == {"FINISHED"}
issues = [i.text for i in s.issues]
for expected in ("Area: an area light", "Plane: particle system", "world World: its lighting"):
    assert any(expected in text for text in issues), (expected, issues)

assert bpy.ops.lightfarm.submit() == {"FINISHED"}
submission = operators.task(scene, "submit")
assert submission.join(120), "the job did not end within 2 minutes"
operators.sync(scene)
status = submission.status
assert not status["error"], status
assert status["state"] == "SUCCEEDED", status
assert s.job_id and s.progress == 1.0, (s.job_id, s.progress)
assert s.output_pattern == os.path.join(args.dir, "frames", "shot_####.exr"), s.output_pattern

assert bpy.ops.lightfarm.fetch() == {"FINISHED"}
fetching = operators.task(scene, "fetch")
assert fetching.join(60), "the fetch did not end within a minute"
assert operators._poll() is None, "the timer stops once every task has ended"
assert not fetching.status["error"], fetching.status
paths = fetching.status["paths"]
assert paths == [os.path.join(args.dir, "frames", f"shot_{f:04d}.exr") for f in (2, 4, 6)], paths
assert paths == [scene.render.frame_path(frame=f) for f in (2, 4, 6)], "named as Blender would"

# The exporter wrote the sphere's keys at frame / render.fps seconds, the time lightfarm poses
# frame f at with the fps the add-on submitted.
glb = os.path.join(args.dir, "export", "scene_Scene.glb")
with open(glb, "rb") as f:
    data = f.read()
gltf = json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])
inputs = {s["input"] for a in gltf["animations"] for s in a["samplers"]}
times = [(gltf["accessors"][i]["min"][0], gltf["accessors"][i]["max"][0]) for i in inputs]
settings = lightfarm_blender.mapping.submit_settings(
    lightfarm_blender.mapping.read_render(scene, bpy.data.filepath))
for first, last in times:
    assert math.isclose(first, 2 / settings["fps"], abs_tol=1e-6), (first, settings["fps"])
    assert math.isclose(last, 6 / settings["fps"], abs_tol=1e-6), (last, settings["fps"])

with open(os.path.join(args.dir, "result.json"), "w") as f:
    json.dump(dict(job_id=s.job_id, glb=glb, paths=paths, issues=issues,
                   flags=lightfarm_blender.mapping.cli_flags(settings), key_times=times), f,
              indent=1)
print("addon_script: ok", s.job_id)
