#!/usr/bin/env python3
"""Writes room.gltf and checker.png: a small room as a modelling tool exports it, for radiosity
against the path tracer (tests/integration/radiosity_vs_path_test.cc).

A 4 x 3 x 4 m box room seen from inside: a floor with a checker texture (8 x 8 texels, nearest
filtering, light and dark grey), principled walls (the white ones with a faint specular layer),
a principled red block on the floor (a meshed object), a point light under
the ceiling and a spot light aimed at the floor with a soft edge. Every material is double-sided.
Run from this folder: python3 make_room.py
"""
import base64
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from gltf_writer import GltfBuffer, png  # noqa: E402

buffer = GltfBuffer()
add = buffer.add


def quad(corner, edge_u, edge_v, uv_scale=1.0):
    """A quad corner + s edge_u + t edge_v, wound so its normal is edge_u x edge_v."""
    p = [tuple(corner[i] + s * edge_u[i] + t * edge_v[i] for i in range(3))
         for s, t in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    uv = [(s * uv_scale, t * uv_scale) for s, t in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    return p, uv, [0, 1, 2, 0, 2, 3]


def primitive(quads, material):
    positions, uvs, indices = [], [], []
    for p, uv, idx in quads:
        base = len(positions)
        positions += p
        uvs += uv
        indices += [base + i for i in idx]
    return {"attributes": {"POSITION": add(positions, "VEC3"), "TEXCOORD_0": add(uvs, "VEC2")},
            "indices": add(indices, "SCALAR", 5123, "H"), "material": material}


W, H, D = 4.0, 3.0, 4.0  # x in [-2, 2], y in [0, 3], z in [-2, 2]
# Inward normals: floor +y, ceiling -y, walls towards the centre.
floor = quad((-2, 0, 2), (4, 0, 0), (0, 0, -4))
ceiling = quad((-2, 3, -2), (4, 0, 0), (0, 0, 4))
back = quad((-2, 0, -2), (4, 0, 0), (0, 3, 0))       # z = -2, normal +z
left = quad((-2, 0, 2), (0, 0, -4), (0, 3, 0))       # x = -2, normal +x
right = quad((2, 0, -2), (0, 0, 4), (0, 3, 0))       # x = 2, normal -x
front = quad((2, 0, 2), (-4, 0, 0), (0, 3, 0))       # z = 2, normal -z


def block(lo, hi):
    """An axis-aligned box, outward normals."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    return [quad((x0, y1, z1), (dx, 0, 0), (0, 0, -dz)),   # top +y
            quad((x0, y0, z0), (dx, 0, 0), (0, 0, dz)),    # bottom -y
            quad((x0, y0, z1), (dx, 0, 0), (0, dy, 0)),    # +z
            quad((x1, y0, z0), (-dx, 0, 0), (0, dy, 0)),   # -z
            quad((x1, y0, z1), (0, 0, -dz), (0, dy, 0)),   # +x
            quad((x0, y0, z0), (0, 0, dz), (0, dy, 0))]    # -x


def principled(name, color, roughness=1.0, specular=0.0, texture=None):
    m = {"name": name, "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": color + [1], "metallicFactor": 0,
                                  "roughnessFactor": roughness}}
    if texture is not None:
        m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": texture}
    if specular != 1.0:
        m["extensions"] = {"KHR_materials_specular": {"specularFactor": specular}}
    return m


materials = [
    principled("checker floor", [1, 1, 1], texture=0),
    # A faint specular layer (F0 0.012) on a bright base: what radiosity drops of it is about a
    # percent of the walls' radiance.
    principled("white plaster", [0.7, 0.7, 0.7], specular=0.3),
    principled("green paint", [0.2, 0.55, 0.25], roughness=0.8),
    principled("red block", [0.7, 0.15, 0.1]),
]
meshes = [
    {"name": "floor", "primitives": [primitive([floor], 0)]},
    {"name": "walls", "primitives": [primitive([ceiling, back, right, front], 1)]},
    {"name": "green wall", "primitives": [primitive([left], 2)]},
    {"name": "block", "primitives": [primitive(block((-0.9, 0, -0.9), (-0.1, 0.8, -0.1)), 3)]},
]

# Checker: 8 x 8 texels of 0.5 m, sRGB 200 and 60.
light, dark = 200, 60
rows = [[c for x in range(8) for c in [light if (x + y) % 2 == 0 else dark] * 3] for y in range(8)]
with open("checker.png", "wb") as f:
    f.write(png(8, 8, rows))


def look_rotation(eye, target):
    """A quaternion turning -z towards target - eye with +y up."""
    f = [target[i] - eye[i] for i in range(3)]
    n = math.sqrt(sum(c * c for c in f))
    f = [c / n for c in f]
    yaw = math.atan2(-f[0], -f[2])
    pitch = math.asin(f[1])
    cy, sy, cp, sp = math.cos(yaw / 2), math.sin(yaw / 2), math.cos(pitch / 2), math.sin(pitch / 2)
    # q = q_yaw(about y) * q_pitch(about x)
    return [cy * sp, sy * cp, -sy * sp, cy * cp]


eye, target = (1.6, 1.9, 1.7), (-0.6, 0.3, -0.8)
spot_pos = (0.8, 2.9, 0.2)
spot_target = (0.3, 0, -0.4)
gltf = {
    "asset": {"version": "2.0", "generator": "make_room.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular"],
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6]}],
    "nodes": [{"mesh": 0}, {"mesh": 1}, {"mesh": 2}, {"mesh": 3},
              {"camera": 0, "translation": list(eye), "rotation": look_rotation(eye, target)},
              {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [-0.5, 2.6, 0.6]},
              {"extensions": {"KHR_lights_punctual": {"light": 1}}, "translation": list(spot_pos),
               "rotation": look_rotation(spot_pos, spot_target)}],
    "cameras": [{"type": "perspective",
                 "perspective": {"yfov": 1.2, "aspectRatio": 1.0, "znear": 0.05}}],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 0.95, 0.85], "intensity": 2000},
        {"type": "spot", "color": [0.85, 0.9, 1], "intensity": 4000,
         "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.9}}]}},
    "materials": materials,
    "textures": [{"source": 0, "sampler": 0}],
    "samplers": [{"magFilter": 9728, "minFilter": 9728}],
    "images": [{"uri": "checker.png"}],
    "meshes": meshes,
    "accessors": buffer.accessors,
    "bufferViews": buffer.views,
    "buffers": [{"byteLength": len(buffer.data),
                 "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(buffer.data).decode()}],
}
with open("room.gltf", "w") as f:
    json.dump(gltf, f, indent=1)
