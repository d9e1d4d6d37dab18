"""Blender-side helpers shared by the scripts that render lightfarm's scenes with Cycles
(tools/khronos_cycles.py, tools/cycles_bench.py): glTF import with Blender's departures from glTF
put back, lightfarm's logged camera, and Cycles' render settings. Runs in Blender 3.4's Python;
a script beside this file imports it after `sys.path.insert(0, os.path.dirname(__file__))`.
"""

import math

import bpy
import mathutils


def gltf_to_blender(v):
    """glTF's +Y-up frame to Blender's +Z-up one, as the glTF importer converts."""
    return mathutils.Vector((v[0], -v[2], v[1]))


def blender_to_gltf(v):
    return mathutils.Vector((v[0], v[2], -v[1]))


def import_gltf(path):
    """Imports a glTF and puts back what Blender's import departs from (follow_gltf)."""
    # Debian 12's Blender 3.4 glTF importer uses numpy.bool, which numpy 1.24 removed.
    import numpy

    if "bool" not in numpy.__dict__:
        numpy.bool = bool
    bpy.ops.import_scene.gltf(filepath=path)
    follow_gltf()


def follow_gltf():
    """Punctual lights get radius 0 (the importer gives them 0.25 m), a primitive without a
    material gets glTF's default material (white, metallic 1, roughness 1; Blender's default is a
    grey diffuse), and a single-sided material (backface culling, which Cycles ignores) becomes
    transparent from behind."""
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


def hide_back(tree, behind="ShaderNodeBsdfTransparent"):
    """Mixes the material's surface shader with `behind` on back faces (Cycles renders
    backface-culled faces: a transparent shader from behind hides them)."""
    output = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output)
    link = output.inputs["Surface"].links[0]
    shader = link.from_socket
    tree.links.remove(link)
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    back = tree.nodes.new(behind)
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    tree.links.new(shader, mix.inputs[1])
    tree.links.new(back.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs["Shader"], output.inputs["Surface"])
    return back


def parse_camera(args):
    """lightfarm's logged camera in glTF's frame (+Y up) as the words
    `persp PX PY PZ TX TY TZ UX UY UZ FOV_Y_DEG` or `ortho ... HALF_HEIGHT`: (kind, numbers)."""
    return args[0], [float(x) for x in args[1:11]]


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


def setup_cycles(scene, spp, threads=2, bounces=None):
    """Cycles on the CPU, SPP samples, unclamped, no denoising, no glossy filter (both biased),
    a box pixel filter one pixel wide, THREADS threads, Standard view transform and a linear
    32-bit float EXR. BOUNCES caps every kind of bounce; None keeps Cycles' defaults."""
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = spp
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.sample_clamp_direct = 0
    cycles.sample_clamp_indirect = 0
    if bounces is not None:
        cycles.max_bounces = bounces
        cycles.diffuse_bounces = cycles.glossy_bounces = cycles.transmission_bounces = bounces
        cycles.transparent_max_bounces = bounces
        cycles.volume_bounces = bounces
    cycles.caustics_reflective = cycles.caustics_refractive = True
    cycles.blur_glossy = 0
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0
    scene.view_settings.gamma = 1
    out = scene.render.image_settings
    out.file_format = "OPEN_EXR"
    out.color_mode = "RGBA"
    out.color_depth = "32"
    out.exr_codec = "ZIP"


def set_world(scene, radiance):
    """A uniform world of this radiance (lightfarm's {"type": "environment", "radiance": R})."""
    world = bpy.data.worlds.new("uniform")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1, 1, 1, 1)
    background.inputs["Strength"].default_value = radiance
    scene.world = world
