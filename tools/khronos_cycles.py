"""Renders a glTF with Blender's Cycles the way tools/khronos_vs_cycles.sh renders it with lightfarm.

    blender -b --factory-startup --python tools/khronos_cycles.py -- \
        SCENE.gltf OUT.exr SIZE SPP CAMERA...

CAMERA is lightfarm's logged camera in glTF's frame (+Y up), as numbers:
    persp PX PY PZ TX TY TZ UX UY UZ FOV_Y_DEG     or     ortho PX PY PZ TX TY TZ UX UY UZ HALF_HEIGHT
Lighting: a uniform white world of radiance 1 (lightfarm's {"type": "environment", "radiance": 1})
plus the file's own KHR_lights_punctual lights (the importer's default, physical units: W = lm /
683, as lightfarm converts). The film is transparent, so OUT.exr's alpha marks where the camera
sees the asset; RGB is linear, Standard view transform (no Filmic), unclamped, no denoising, a box
pixel filter, bounces up to 64 (lightfarm's are unlimited with Russian roulette).

Where Blender's import departs from glTF, tools/cycles_scene.py puts glTF back: punctual lights get radius 0
(the importer gives them 0.25 m), a primitive without a material gets glTF's default material
(white, metallic 1, roughness 1; Blender's default is a grey diffuse), and a single-sided material
(backface culling, which Cycles ignores) becomes transparent from behind.

Also prints "AUTO PX PY PZ TX TY TZ FOV" : lightfarm's --camera auto framing (auto_camera.cc)
computed here from the imported meshes' bounds, for the script to check against lightfarm's.
"""

import math
import os
import sys
import time

import bpy
import mathutils

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_scene  # noqa: E402  (beside this file, found through the path just set)


def auto_framing():
    """FrameScene: the bounding sphere of every mesh vertex seen from 20 degrees above glTF's front."""
    lo = mathutils.Vector((math.inf,) * 3)
    hi = mathutils.Vector((-math.inf,) * 3)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH":
            continue
        mesh = obj.evaluated_get(depsgraph).data
        for vertex in mesh.vertices:
            p = cycles_scene.blender_to_gltf(obj.matrix_world @ vertex.co)
            lo = mathutils.Vector(map(min, lo, p))
            hi = mathutils.Vector(map(max, hi, p))
    centre = (lo + hi) / 2
    radius = (hi - lo).length / 2 or 1
    elevation = math.radians(20)
    distance = radius / math.sin(math.radians(20))
    position = centre + mathutils.Vector((0, math.sin(elevation), math.cos(elevation))) * distance
    return position, centre


def main():
    args = sys.argv[sys.argv.index("--") + 1 :]
    gltf, out, size, spp = args[0], args[1], int(args[2]), int(args[3])
    kind, numbers = cycles_scene.parse_camera(args[4:15])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    cycles_scene.import_gltf(gltf)
    scene = bpy.context.scene
    position, target = auto_framing()
    print("AUTO %.6g %.6g %.6g %.6g %.6g %.6g 40" % (*position, *target))
    cycles_scene.set_camera(scene, kind, numbers, size)
    cycles_scene.setup_cycles(scene, spp, bounces=64)
    scene.render.film_transparent = True
    cycles_scene.set_world(scene, 1)
    scene.render.filepath = out
    start = time.time()
    bpy.ops.render.render(write_still=True)
    print("CYCLES_SECONDS %.2f" % (time.time() - start))


main()
