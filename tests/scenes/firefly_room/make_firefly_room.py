#!/usr/bin/env python3
"""Writes firefly_room.json and uv_sphere.obj: issue 28's Blender room in small.

A floor, smooth-shaded low-poly UV spheres (16 x 8 segments, per-vertex normals) of every
material kind, a small emissive panel of radiance 8, and point, spot and directional lights.
Run from anywhere; the files land beside this script.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def uv_sphere(segments=16, rings=8):
    """A unit UV sphere as Blender builds it: poles plus (rings - 1) latitude circles."""
    verts, normals, uvs, faces = [], [], [], []
    for i in range(rings + 1):
        theta = math.pi * i / rings
        for j in range(segments + 1):
            phi = 2 * math.pi * j / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            verts.append(n)
            normals.append(n)
            uvs.append((j / segments, 1 - i / rings))
    row = segments + 1
    for i in range(rings):
        for j in range(segments):
            a, b = i * row + j, i * row + j + 1
            c, d = (i + 1) * row + j + 1, (i + 1) * row + j
            if i != 0:
                faces.append((a, d, b))
            if i != rings - 1:
                faces.append((b, d, c))
    lines = ["# 16 x 8 UV sphere, smooth normals (make_firefly_room.py)"]
    lines += ["v %.6f %.6f %.6f" % v for v in verts]
    lines += ["vt %.6f %.6f" % t for t in uvs]
    lines += ["vn %.6f %.6f %.6f" % n for n in normals]
    for f in faces:
        lines.append("f " + " ".join("%d/%d/%d" % (k + 1, k + 1, k + 1) for k in f))
    return "\n".join(lines) + "\n"


def sphere(name, material, center, radius):
    return {"type": "mesh", "name": name, "material": material, "file": "uv_sphere.obj",
            "transform": {"scale": radius, "translate": center}}


def scene():
    materials = {
        "floor": {"type": "principled", "base_color": [0.6, 0.55, 0.5], "roughness": 0.5},
        "gold": {"type": "principled", "base_color": [1.0, 0.766, 0.336], "metallic": 1,
                 "roughness": 0.3},
        "glass": {"type": "principled", "transmission": 1, "roughness": 0, "ior": 1.5,
                  "thickness": 1},
        "thin_glass": {"type": "principled", "transmission": 1, "roughness": 0, "ior": 1.5},
        "plastic": {"type": "principled", "base_color": [0.1, 0.3, 0.8], "roughness": 0.5},
        "chrome": {"type": "principled", "base_color": [0.95, 0.95, 0.95], "metallic": 1,
                   "roughness": 0},
        "lambert": {"type": "lambert", "reflectance": [0.8, 0.8, 0.8]},
        "mirror": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]},
        "dielectric": {"type": "dielectric", "ior": 1.5},
        "glossy": {"type": "glossy", "roughness": 0.3, "reflectance": [0.9, 0.6, 0.3]},
        "panel": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [8, 8, 8]},
    }
    shapes = [
        {"type": "quad", "name": "floor", "material": "floor",
         "vertices": [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]},
        {"type": "quad", "name": "panel", "material": "panel",
         "vertices": [[-0.3, 2.5, -0.3], [0.3, 2.5, -0.3], [0.3, 2.5, 0.3], [-0.3, 2.5, 0.3]]},
    ]
    names = ["gold", "glass", "thin_glass", "plastic", "chrome", "lambert", "mirror",
             "dielectric", "glossy"]
    for k, name in enumerate(names):
        x = -2.0 + 1.0 * (k % 5)
        z = -0.6 + 1.2 * (k // 5)
        shapes.append(sphere(name, name, [x, 0.45, z], 0.45))
    lights = [
        {"type": "point", "position": [1.5, 2.0, 1.5], "intensity": 4},
        {"type": "spot", "position": [-1.5, 2.2, 1.8], "direction": [0.5, -1, -0.8],
         "intensity": 6, "outer_angle_deg": 40, "inner_angle_deg": 30},
        {"type": "directional", "direction": [-1, -2, -0.5], "irradiance": 2},
    ]
    camera = {"position": [0, 1.6, 4.2], "look_at": [0, 0.4, 0], "up": [0, 1, 0],
              "fov_y_deg": 45, "resolution": [96, 64]}
    return {"camera": camera, "materials": materials, "shapes": shapes, "lights": lights}


def main():
    with open(os.path.join(HERE, "uv_sphere.obj"), "w") as f:
        f.write(uv_sphere())
    with open(os.path.join(HERE, "firefly_room.json"), "w") as f:
        json.dump(scene(), f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
