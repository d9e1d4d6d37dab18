#!/usr/bin/env python3
"""Writes multi_uv.gltf: two emissive quads facing a camera on +z, whose emission textures read
TEXCOORD_1 (left quad, in [-1, 0] x [-1, 1]) and TEXCOORD_0 (right quad, in [0, 1] x [-1, 1]).

The texture is 2x1 texels, red then green, nearest-filtered. On both quads TEXCOORD_0 puts the
whole quad in the red texel and TEXCOORD_1 in the green one, so the left quad shows green only
when TEXCOORD_1 is read, and the right quad shows red (its TEXCOORD_1 is not kept).
Run from this folder: python3 make_multi_uv.py
"""
import base64
import json
import os
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from gltf_writer import png  # noqa: E402


def quad(x0, x1):
    """Positions (4 vec3), uv0 and uv1 (4 vec2 each) of a quad over [x0, x1] x [-1, 1]."""
    positions = [(x0, 1, 0), (x0, -1, 0), (x1, -1, 0), (x1, 1, 0)]
    uv0 = [(0.25, 0.5)] * 4  # the red texel's centre
    uv1 = [(0.75, 0.5)] * 4  # the green texel's centre
    return positions, uv0, uv1


data = bytearray()
accessors, views = [], []


def add(values, kind):
    flat = [c for v in values for c in v]
    offset = len(data)
    data.extend(struct.pack("<%df" % len(flat), *flat))
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": 4 * len(flat)})
    accessor = {"bufferView": len(views) - 1, "componentType": 5126, "count": len(values),
                "type": kind}
    if kind == "VEC3":
        accessor["min"] = [min(v[i] for v in values) for i in range(3)]
        accessor["max"] = [max(v[i] for v in values) for i in range(3)]
    accessors.append(accessor)
    return len(accessors) - 1


offset = len(data)
data.extend(struct.pack("<6H", 0, 1, 2, 0, 2, 3))
data.extend(b"\0\0")  # keep the floats 4-byte aligned
views.append({"buffer": 0, "byteOffset": offset, "byteLength": 12})
accessors.append({"bufferView": 0, "componentType": 5123, "count": 6, "type": "SCALAR"})

primitives = []
for material, (x0, x1) in enumerate([(-1, 0), (0, 1)]):
    positions, uv0, uv1 = quad(x0, x1)
    primitives.append({"attributes": {"POSITION": add(positions, "VEC3"),
                                      "TEXCOORD_0": add(uv0, "VEC2"),
                                      "TEXCOORD_1": add(uv1, "VEC2")},
                       "indices": 0, "material": material})


def emissive(name, tex_coord):
    return {"name": name,
            "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
            "emissiveFactor": [1, 1, 1],
            "emissiveTexture": {"index": 0, "texCoord": tex_coord}}


image = png(2, 1, [[255, 0, 0, 0, 255, 0]])
gltf = {
    "asset": {"version": "2.0", "generator": "make_multi_uv.py"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1]}],
    "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 1]}],
    "cameras": [{"type": "perspective",
                 "perspective": {"yfov": 1.5707963267948966, "aspectRatio": 1, "znear": 0.01}}],
    "meshes": [{"name": "quads", "primitives": primitives}],
    "materials": [emissive("reads TEXCOORD_1", 1), emissive("reads TEXCOORD_0", 0)],
    "samplers": [{"magFilter": 9728, "minFilter": 9728}],
    "images": [{"uri": "data:image/png;base64," + base64.b64encode(image).decode()}],
    "textures": [{"source": 0, "sampler": 0}],
    "buffers": [{"byteLength": len(data),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
    "bufferViews": views,
    "accessors": accessors,
}
with open("multi_uv.gltf", "w") as f:
    json.dump(gltf, f, indent=1)
    f.write("\n")
