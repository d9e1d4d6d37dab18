"""The Cycles side of tools/cycles_bench.sh: loads one of lightfarm's scenes into Blender once and
renders it several times with Cycles, timing each render call alone.

    blender -b --factory-startup --python tools/cycles_bench.py -- \
        SCENE OUTDIR SIZE THREADS CAMERA... RENDER...

SCENE is a glTF (imported as tools/cycles_scene.py does, Blender's departures from glTF put back)
or a JSON scene of quads with lambert materials (tests/scenes/cornell_box.json, many_lights.json):
each quad becomes a mesh face with the same vertex order (front faces agree), each material a
diffuse BSDF of its reflectance; an emission adds an emission shader of that radiance on the
front face only, as lightfarm's lambert emission is one-sided. No world: the background is black,
as in those scenes. CAMERA is lightfarm's logged camera (cycles_scene.parse_camera's 11 words).
Each RENDER is NAME:SPP:SEED[:THRESHOLD]: SPP samples with Cycles' seed SEED, or with THRESHOLD
adaptive sampling at that noise threshold (its default minimum samples, SPP the most), written
to OUTDIR/NAME.exr; prints "CYCLES_SECONDS NAME S", S the wall time of bpy.ops.render.render
(sync, BVH, render and the EXR's write; Blender's start-up and the import are not counted).
"""

import json
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_scene  # noqa: E402  (beside this file, found through the path just set)


# Every kind of bounce up to 64, as tools/khronos_cycles.py: Cycles' defaults (4 diffuse, 4 glossy)
# cut the light of longer paths, which lightfarm's unlimited depth with roulette keeps (1.4 % on the
# Cornell box), and would compare a cheaper, biased estimator with an unbiased one.
BOUNCES = 64

def lambert(name, spec):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    output = tree.nodes["Material Output"]
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*spec.get("reflectance", (0.5, 0.5, 0.5)), 1)
    tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    emission = spec.get("emission")
    if emission and any(emission):
        light = tree.nodes.new("ShaderNodeEmission")
        light.inputs["Color"].default_value = (*emission, 1)
        light.inputs["Strength"].default_value = 1
        add = tree.nodes.new("ShaderNodeAddShader")
        tree.links.new(diffuse.outputs["BSDF"], add.inputs[0])
        tree.links.new(light.outputs["Emission"], add.inputs[1])
        tree.links.new(add.outputs["Shader"], output.inputs["Surface"])
        # From behind: the diffuse BSDF alone.
        back = cycles_scene.hide_back(tree, "ShaderNodeBsdfDiffuse")
        back.inputs["Color"].default_value = diffuse.inputs["Color"].default_value
    return material


def build_json(path):
    with open(path) as f:
        scene = json.load(f)
    materials = {name: lambert(name, spec) for name, spec in scene.get("materials", {}).items()}
    vertices, faces, face_materials = [], [], []
    order = list(materials)
    for i, shape in enumerate(scene.get("shapes", [])):
        if shape.get("type") != "quad":
            kind = shape.get("type")
            sys.exit("%s: shapes[%d]: type %r: only quads are built here" % (path, i, kind))
        if shape.get("material") not in materials:
            sys.exit("%s: shapes[%d]: no material %r" % (path, i, shape.get("material")))
        faces.append(range(len(vertices), len(vertices) + 4))
        vertices.extend(cycles_scene.gltf_to_blender(v) for v in shape["vertices"])
        face_materials.append(order.index(shape["material"]))
    mesh = bpy.data.meshes.new(os.path.basename(path))
    mesh.from_pydata(vertices, [], [list(f) for f in faces])
    for material in materials.values():
        mesh.materials.append(material)
    for polygon, index in zip(mesh.polygons, face_materials):
        polygon.material_index = index
    obj = bpy.data.objects.new(mesh.name, mesh)
    bpy.context.scene.collection.objects.link(obj)


def main():
    args = sys.argv[sys.argv.index("--") + 1 :]
    path, outdir, size, threads = args[0], args[1], int(args[2]), int(args[3])
    kind, numbers = cycles_scene.parse_camera(args[4:15])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.endswith(".json"):
        build_json(path)
    else:
        cycles_scene.import_gltf(path)
    scene = bpy.context.scene
    cycles_scene.set_camera(scene, kind, numbers, size)
    for render in args[15:]:
        name, spp, seed, *threshold = render.split(":")
        cycles_scene.setup_cycles(scene, int(spp), threads, bounces=BOUNCES)
        scene.cycles.seed = int(seed)
        scene.cycles.use_animated_seed = False
        if threshold:
            scene.cycles.use_adaptive_sampling = True
            scene.cycles.adaptive_threshold = float(threshold[0])
        scene.render.filepath = os.path.join(outdir, name + ".exr")
        start = time.time()
        bpy.ops.render.render(write_still=True)
        print("CYCLES_SECONDS %s %.3f" % (name, time.time() - start), flush=True)


main()
