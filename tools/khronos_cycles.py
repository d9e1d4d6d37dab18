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

Where Blender's import departs from glTF, the script puts glTF back: punctual lights get radius 0
(the importer gives them 0.25 m), a primitive without a material gets glTF's default material
(white, metallic 1, roughness 1; Blender's default is a grey diffuse), and a single-sided material
(backface culling, which Cycles ignores) becomes transparent from behind.

Also prints "AUTO PX PY PZ TX TY TZ FOV" : lightfarm's --camera auto framing (auto_camera.cc)
computed here from the imported meshes' bounds, for the script to check against lightfarm's.
"""

import math
import sys
import time

import bpy
import mathutils


def gltf_to_blender(v):
    """glTF's +Y-up frame to Blender's +Z-up one, as the glTF importer converts."""
    return mathutils.Vector((v[0], -v[2], v[1]))


def blender_to_gltf(v):
    return mathutils.Vector((v[0], v[2], -v[1]))


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
            p = blender_to_gltf(obj.matrix_world @ vertex.co)
            lo = mathutils.Vector(map(min, lo, p))
            hi = mathutils.Vector(map(max, hi, p))
    centre = (lo + hi) / 2
    radius = (hi - lo).length / 2 or 1
    elevation = math.radians(20)
    distance = radius / math.sin(math.radians(20))
    position = centre + mathutils.Vector((0, math.sin(elevation), math.cos(elevation))) * distance
    return position, centre


def follow_gltf():
    for light in bpy.data.lights:
        light.shadow_soft_size = 0
        if light.type == "SUN":
            light.angle = 0
    default = None
    for obj in bpy.context.scene.objects:
        if obj.type == "MESH" and not any(slot.material for slot in obj.material_slots):
            if default is None:
                default = bpy.data.materials.new("gltf default")
                default.use_nodes = True
                bsdf = default.node_tree.nodes["Principled BSDF"]
                bsdf.inputs["Base Color"].default_value = (1, 1, 1, 1)
                bsdf.inputs["Metallic"].default_value = 1
                bsdf.inputs["Roughness"].default_value = 1
                default.use_backface_culling = True
            obj.data.materials.clear()
            obj.data.materials.append(default)
    for material in bpy.data.materials:
        if material.use_backface_culling and material.use_nodes:
            hide_back(material.node_tree)


def hide_back(tree):
    """Cycles renders backface-culled faces: a transparent shader from behind hides them."""
    output = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output)
    link = output.inputs["Surface"].links[0]
    shader = link.from_socket
    tree.links.remove(link)
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    clear = tree.nodes.new("ShaderNodeBsdfTransparent")
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    tree.links.new(shader, mix.inputs[1])
    tree.links.new(clear.outputs["BSDF"], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], output.inputs["Surface"])


def set_camera(scene, kind, numbers, size):
    position, target, up = (mathutils.Vector(numbers[i : i + 3]) for i in (0, 3, 6))
    data = bpy.data.cameras.new("lightfarm")
    data.sensor_fit = "VERTICAL"
    if kind == "ortho":
        data.type = "ORTHO"
        data.ortho_scale = 2 * numbers[9]  # Blender's scale is the (vertical, here) full size
    else:
        data.angle_y = math.radians(numbers[9])
    data.clip_start, data.clip_end = 1e-4, 1e6
    camera = bpy.data.objects.new("lightfarm", data)
    scene.collection.objects.link(camera)
    eye, look = gltf_to_blender(position), gltf_to_blender(target)
    camera.location = eye
    # -Z looks at the target, +Y leans towards the given up.
    forward = (look - eye).normalized()
    up_b = gltf_to_blender(up)
    right = forward.cross(up_b).normalized()
    true_up = right.cross(forward)
    rotation = mathutils.Matrix((right, true_up, -forward)).transposed()
    camera.rotation_euler = rotation.to_euler()
    scene.camera = camera
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100


def setup_cycles(scene, spp):
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = spp
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.sample_clamp_direct = 0
    cycles.sample_clamp_indirect = 0
    cycles.max_bounces = 64
    cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = 64
    cycles.transparent_max_bounces = 64
    cycles.volume_bounces = 64
    cycles.caustics_reflective = cycles.caustics_refractive = True
    cycles.blur_glossy = 0
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0
    scene.view_settings.gamma = 1
    world = bpy.data.worlds.new("white")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1, 1, 1, 1)
    background.inputs["Strength"].default_value = 1
    scene.world = world
    out = scene.render.image_settings
    out.file_format = "OPEN_EXR"
    out.color_mode = "RGBA"
    out.color_depth = "32"
    out.exr_codec = "ZIP"


def main():
    args = sys.argv[sys.argv.index("--") + 1 :]
    gltf, out, size, spp, kind = args[0], args[1], int(args[2]), int(args[3]), args[4]
    numbers = [float(x) for x in args[5:15]]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    # Debian 12's Blender 3.4 glTF importer uses numpy.bool, which numpy 1.24 removed.
    import numpy

    if "bool" not in numpy.__dict__:
        numpy.bool = bool
    bpy.ops.import_scene.gltf(filepath=gltf)
    scene = bpy.context.scene
    follow_gltf()
    position, target = auto_framing()
    print("AUTO %.6g %.6g %.6g %.6g %.6g %.6g 40" % (*position, *target))
    set_camera(scene, kind, numbers, size)
    setup_cycles(scene, spp)
    scene.render.filepath = out
    start = time.time()
    bpy.ops.render.render(write_still=True)
    print("CYCLES_SECONDS %.2f" % (time.time() - start))


main()
