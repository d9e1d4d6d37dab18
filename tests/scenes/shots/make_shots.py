#!/usr/bin/env python3
"""Writes the animated glTF scenes of tests/scenes/shots (stdlib only; run from anywhere):

moving_ball.gltf         an emissive UV sphere (radius 0.3, emission 1) whose node moves on a
                         LINEAR translation channel from BALL_FROM at 0 s to BALL_TO at 1 s, seen
                         by a still perspective camera at CAMERA_FROM looking down -Z
                         (yfov 0.8 rad, aspect 4:3); no lights, black background.
moving_ball_camera.gltf  the same, the camera node also moving (LINEAR) from CAMERA_FROM at 0 s
                         to CAMERA_TO at 1 s.

tests/integration/shot_render_test.cc repeats these numbers to predict where the ball is.
"""
import base64
import json
import math
import os
import struct

BALL_RADIUS = 0.3
BALL_FROM, BALL_TO = (-1.5, -0.5, 0.0), (1.5, 0.5, 0.0)
CAMERA_FROM, CAMERA_TO = (0.0, 0.0, 5.0), (0.5, 0.3, 5.0)
YFOV, ASPECT = 0.8, 4.0 / 3.0
SEGMENTS, RINGS = 48, 24


def uv_sphere(radius):
    positions, normals, indices = [], [], []
    for r in range(RINGS + 1):
        theta = math.pi * r / RINGS
        for s in range(SEGMENTS + 1):
            phi = 2 * math.pi * s / SEGMENTS
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
            normals.append(n)
            positions.append(tuple(radius * c for c in n))
    row = SEGMENTS + 1
    for r in range(RINGS):
        for s in range(SEGMENTS):
            a, b = r * row + s, (r + 1) * row + s
            # Counter-clockwise seen from outside.
            if r > 0:
                indices += [a, a + 1, b]
            if r < RINGS - 1:
                indices += [a + 1, b + 1, b]
    return positions, normals, indices


class Buffer:
    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []

    def add(self, fmt, rows, component, kind, target=None, minmax=False):
        while len(self.data) % 4:
            self.data.append(0)
        start = len(self.data)
        for row in rows:
            self.data += struct.pack("<" + fmt, *(row if isinstance(row, tuple) else (row,)))
        view = {"buffer": 0, "byteOffset": start, "byteLength": len(self.data) - start}
        if target:
            view["target"] = target
        self.views.append(view)
        accessor = {"bufferView": len(self.views) - 1, "componentType": component,
                    "count": len(rows), "type": kind}
        if minmax:
            columns = list(zip(*[r if isinstance(r, tuple) else (r,) for r in rows]))
            accessor["min"] = [min(c) for c in columns]
            accessor["max"] = [max(c) for c in columns]
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def scene(moving_camera):
    buf = Buffer()
    positions, normals, indices = uv_sphere(BALL_RADIUS)
    pos = buf.add("3f", positions, 5126, "VEC3", 34962, minmax=True)
    nrm = buf.add("3f", normals, 5126, "VEC3", 34962)
    idx = buf.add("H", indices, 5123, "SCALAR", 34963)
    times = buf.add("f", [0.0, 1.0], 5126, "SCALAR", minmax=True)
    ball_keys = buf.add("3f", [BALL_FROM, BALL_TO], 5126, "VEC3")
    samplers = [{"input": times, "output": ball_keys, "interpolation": "LINEAR"}]
    channels = [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]
    if moving_camera:
        camera_keys = buf.add("3f", [CAMERA_FROM, CAMERA_TO], 5126, "VEC3")
        samplers.append({"input": times, "output": camera_keys, "interpolation": "LINEAR"})
        channels.append({"sampler": 1, "target": {"node": 1, "path": "translation"}})
    return {
        "asset": {"version": "2.0", "generator": "lightfarm tests/scenes/shots/make_shots.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "ball", "mesh": 0, "translation": list(BALL_FROM)},
            {"name": "camera", "camera": 0, "translation": list(CAMERA_FROM)},
        ],
        "meshes": [{"name": "ball", "primitives": [
            {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": 0}]}],
        "materials": [{"name": "glow", "emissiveFactor": [1.0, 1.0, 1.0],
                       "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1],
                                                "metallicFactor": 0}}],
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": YFOV, "aspectRatio": ASPECT, "znear": 0.1}}],
        "animations": [{"name": "move", "samplers": samplers, "channels": channels}],
        "buffers": [{"byteLength": len(buf.data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(bytes(buf.data)).decode("ascii")}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    }


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    for name, moving_camera in (("moving_ball.gltf", False), ("moving_ball_camera.gltf", True)):
        with open(os.path.join(here, name), "w") as f:
            json.dump(scene(moving_camera), f, separators=(",", ":"))
            f.write("\n")


if __name__ == "__main__":
    main()
