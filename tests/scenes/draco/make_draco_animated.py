#!/usr/bin/env python3
"""Writes animated_draco.glb: one mesh of two KHR_draco_mesh_compression primitives (a unit
UV sphere, edgebreaker, and a smaller sphere of radius 0.5 around (2.5, 0, 0), sequential
connectivity: different point counts), used by three nodes that a 1 s animation moves in the
three ways glTF can:
  - "Skinned": skinned to the joint "Bone" (identity inverse bind), which moves from (0, 0, 0)
    to (0, 2, 0);
  - "Rigid": its own translation from (0, 0, -5) to (3, 0, -5);
  - "Morphed": at (0, 0, 5), its weights channel 0 to 1 on the one morph target, which lifts
    every vertex by (0, 0, 1).
JOINTS_0, WEIGHTS_0 and the morph target are plain accessors, the same for every vertex (all
on joint 0 at weight 1, every delta (0, 0, 1)), so they hold whatever order the Draco decoder
gives the points. Posed at t, every vertex is its rest position plus the node's motion at t.
Compressed by Debian's draco_encoder (package `draco`); CI has no encoder, so the output is
committed. Run from anywhere:
  python3 tests/scenes/draco/make_draco_animated.py
"""
import json
import os
import struct

from make_draco_twins import HERE, encode, glb, sphere


def primitive_stream(segments, rings, scale, offset, level):
    vertices, triangles = sphere(segments, rings)
    moved = [(tuple(scale * p[i] + offset[i] for i in range(3)), n, uv) for p, n, uv in vertices]
    return moved, triangles, encode(moved, triangles, level)


def main():
    blob = bytearray()
    views, accessors = [], []

    def view(data):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob.extend(data)
        return len(views) - 1

    def accessor(count, kind, component=5126, data=None, **extra):
        a = {"componentType": component, "count": count, "type": kind, **extra}
        if data is not None:
            a["bufferView"] = view(data)
        accessors.append(a)
        return len(accessors) - 1

    primitives = []
    for segments, rings, scale, offset, level in ((16, 10, 1.0, (0, 0, 0), 7),
                                                  (8, 6, 0.5, (2.5, 0, 0), 0)):
        vertices, triangles, stream = primitive_stream(segments, rings, scale, offset, level)
        n = len(vertices)
        stream_view = view(stream)
        position = accessor(n, "VEC3", min=[min(v[0][i] for v in vertices) for i in range(3)],
                            max=[max(v[0][i] for v in vertices) for i in range(3)])
        uv = accessor(n, "VEC2")
        normal = accessor(n, "VEC3")
        indices = accessor(3 * len(triangles), "SCALAR", 5125)
        joints = accessor(n, "VEC4", 5121, bytes(4 * n))
        weights = accessor(n, "VEC4", 5126, struct.pack("<4f", 1, 0, 0, 0) * n)
        lift = accessor(n, "VEC3", 5126, struct.pack("<3f", 0, 0, 1) * n,
                        min=[0, 0, 1], max=[0, 0, 1])
        primitives.append({
            # draco_encoder numbers an OBJ's attributes position, texture coordinate, normal.
            "attributes": {"POSITION": position, "TEXCOORD_0": uv, "NORMAL": normal,
                           "JOINTS_0": joints, "WEIGHTS_0": weights},
            "indices": indices,
            "targets": [{"POSITION": lift}],
            "extensions": {"KHR_draco_mesh_compression": {
                "bufferView": stream_view,
                "attributes": {"POSITION": 0, "TEXCOORD_0": 1, "NORMAL": 2}}},
        })

    times = accessor(2, "SCALAR", 5126, struct.pack("<2f", 0, 1), min=[0], max=[1])
    bone_moves = accessor(2, "VEC3", 5126, struct.pack("<6f", 0, 0, 0, 0, 2, 0))
    rigid_moves = accessor(2, "VEC3", 5126, struct.pack("<6f", 0, 0, -5, 3, 0, -5))
    weights = accessor(2, "SCALAR", 5126, struct.pack("<2f", 0, 1))
    j = {
        "asset": {"version": "2.0", "generator": "tests/scenes/draco/make_draco_animated.py"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"name": "Bone"},
            {"name": "Skinned", "mesh": 0, "skin": 0},
            {"name": "Rigid", "mesh": 0, "translation": [0, 0, -5]},
            {"name": "Morphed", "mesh": 0, "translation": [0, 0, 5]},
        ],
        "skins": [{"joints": [0]}],
        "meshes": [{"name": "twins", "primitives": primitives, "weights": [0]}],
        "animations": [{"name": "Action", "samplers": [
            {"input": times, "output": bone_moves},
            {"input": times, "output": rigid_moves},
            {"input": times, "output": weights},
        ], "channels": [
            {"sampler": 0, "target": {"node": 0, "path": "translation"}},
            {"sampler": 1, "target": {"node": 2, "path": "translation"}},
            {"sampler": 2, "target": {"node": 3, "path": "weights"}},
        ]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    with open(os.path.join(HERE, "animated_draco.glb"), "wb") as f:
        f.write(glb(j, bytes(blob)))
    print("%d bytes" % len(blob))


if __name__ == "__main__":
    main()
