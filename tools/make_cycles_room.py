"""Builds the textured room of tools/cycles_bench.sh in Blender and writes it with Blender's glTF
exporter to tests/scenes/cycles_room/ (room.gltf, room.bin, bricks.png), so that lightfarm and
Cycles (which imports the glTF again) render one scene:

    blender -b --factory-startup --python tools/make_cycles_room.py [-- OUTDIR]

A closed 4 x 4 x 2.8 m room: walls of a 64 x 64 brick texture repeated once a metre, a grey
floor, a white ceiling with a 1 x 1 m emissive panel (one-sided, facing down, radiance 8, 7, 6
W m^-2 sr^-1 through KHR_materials_emissive_strength) as the only light, a glass sphere
(smooth, KHR_materials_transmission, IOR 1.5: glTF's default), a rough gold metal sphere, and
the camera. The glass gets KHR_materials_volume after the export (make_glass_solid), so that
lightfarm refracts through it as Cycles does. Running it again writes the same scene (the
spheres' smooth normals may differ in their last bits: Blender computes them in parallel).
"""

import json
import math
import os
import sys

import bpy
import mathutils

HALF, HEIGHT = 2.0, 2.8


def material(name, color, roughness, metallic=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    return m, bsdf


def brick_image():
    """64 x 64 pixels, two courses of bricks 32 x 16 with 2-pixel mortar, offset by half a brick."""
    size = 64
    image = bpy.data.images.new("bricks", size, size, alpha=False)
    pixels = []
    for y in range(size):
        course = y // 16
        for x in range(size):
            xs = (x + 16 * (course % 2)) % size
            if y % 16 < 2 or xs % 32 < 2:
                rgb = (0.75, 0.73, 0.68)  # mortar
            else:
                brick = (course * 7 + xs // 32 * 3) % 5  # a few shades, no randomness
                rgb = (0.55 + 0.05 * brick, 0.22 + 0.02 * brick, 0.15)
            pixels.extend((*rgb, 1.0))
    image.pixels = pixels
    image.file_format = "PNG"
    image.pack()  # the exporter writes it beside the glTF as bricks.png
    return image


def room():
    walls, _ = material("Bricks", (1, 1, 1), 0.8)
    tree = walls.node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = brick_image()
    tree.links.new(texture.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    floor, _ = material("Floor", (0.4, 0.4, 0.4), 0.5)
    ceiling, _ = material("Ceiling", (0.8, 0.8, 0.8), 1.0)
    h, z = HALF, HEIGHT
    quads = [
        ((-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0), floor),
        ((-h, -h, z), (h, -h, z), (h, h, z), (-h, h, z), ceiling),
        ((-h, h, 0), (h, h, 0), (h, h, z), (-h, h, z), walls),
        ((-h, -h, 0), (h, -h, 0), (h, -h, z), (-h, -h, z), walls),
        ((-h, -h, 0), (-h, h, 0), (-h, h, z), (-h, -h, z), walls),
        ((h, -h, 0), (h, h, 0), (h, h, z), (h, -h, z), walls),
    ]
    mesh = bpy.data.meshes.new("Room")
    vertices = [v for q in quads for v in q[:4]]
    mesh.from_pydata(vertices, [], [range(4 * i, 4 * i + 4) for i in range(len(quads))])
    order = [floor, ceiling, walls]
    for m in order:
        mesh.materials.append(m)
    uv = mesh.uv_layers.new(name="UVMap")
    centre = mathutils.Vector((0, 0, z / 2))
    for polygon, quad in zip(mesh.polygons, quads):
        if polygon.normal.dot(centre - polygon.center) < 0:
            polygon.flip()  # every face looks into the room
        polygon.material_index = order.index(quad[4])
        for loop in polygon.loop_indices:
            co = mesh.vertices[mesh.loops[loop].vertex_index].co
            vertical = abs(polygon.normal.z) < 0.5
            # One texture tile a metre: along the wall and up, or x and y on floor and ceiling.
            uv.data[loop].uv = (co.x + co.y, co.z) if vertical else (co.x, co.y)
    mesh.update()
    bpy.context.scene.collection.objects.link(bpy.data.objects.new("Room", mesh))


def panel():
    lamp, bsdf = material("Lamp", (0, 0, 0), 1.0)
    bsdf.inputs["Emission"].default_value = (1, 0.875, 0.75, 1)
    bsdf.inputs["Emission Strength"].default_value = 8
    lamp.use_backface_culling = True  # single-sided: emits downwards only, as in lightfarm
    mesh = bpy.data.meshes.new("Panel")
    z = HEIGHT - 0.01
    corners = [(-0.5, -0.5, z), (-0.5, 0.5, z), (0.5, 0.5, z), (0.5, -0.5, z)]
    mesh.from_pydata(corners, [], [range(4)])
    mesh.materials.append(lamp)
    mesh.update()
    assert mesh.polygons[0].normal.z < 0
    bpy.context.scene.collection.objects.link(bpy.data.objects.new("Panel", mesh))


def sphere(name, centre, radius, mat):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=radius, location=centre)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(mat)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    directory = args[0] if args else os.path.join(here, "..", "tests", "scenes", "cycles_room")
    os.makedirs(directory, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    room()
    panel()
    glass, bsdf = material("Glass", (1, 1, 1), 0.0)
    bsdf.inputs["Transmission"].default_value = 1
    bsdf.inputs["IOR"].default_value = 1.5
    sphere("Glass", (-0.7, 0.4, 0.5), 0.5, glass)
    gold, _ = material("Gold", (1.0, 0.77, 0.34), 0.25, metallic=1)
    sphere("Gold", (0.8, 0.9, 0.45), 0.45, gold)
    scene = bpy.context.scene
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.sensor_fit = "VERTICAL"
    camera.data.angle_y = math.radians(60)
    camera.location = (0, -1.9, 1.3)
    towards = mathutils.Vector((0, 0.6, 0.6)) - camera.location
    camera.rotation_euler = towards.to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.resolution_x = scene.render.resolution_y = 256
    path = os.path.join(directory, "room.gltf")
    bpy.ops.export_scene.gltf(
        filepath=path,
        export_format="GLTF_SEPARATE",
        export_cameras=True,
        export_lights=False,
        export_extras=False,
    )
    make_glass_solid(path)


def make_glass_solid(path):
    """glTF's transmission without KHR_materials_volume is a thin wall (no refraction), which
    lightfarm follows; Cycles refracts through the closed sphere whatever glTF says. Blender 3.4's
    exporter writes no volume, so the Glass material gets one here (thickness: the diameter), and
    both renderers see a solid glass ball."""
    with open(path) as f:
        gltf = json.load(f)
    for m in gltf["materials"]:
        if m["name"] == "Glass":
            m.setdefault("extensions", {})["KHR_materials_volume"] = {"thicknessFactor": 1.0}
    used = gltf.setdefault("extensionsUsed", [])
    if "KHR_materials_volume" not in used:
        used.append("KHR_materials_volume")
    with open(path, "w") as f:
        json.dump(gltf, f, indent=4)
        f.write("\n")


main()
