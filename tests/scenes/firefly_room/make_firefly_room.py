#!/usr/bin/env python3
"""Writes firefly_room.json and uv_sphere.obj: issue 28's Blender room in small.

A floor, smooth-shaded low-poly UV spheres (16 x 8 segments, per-vertex normals) of every
material kind (a clear-coated one among them, and a board of the same clear-coated paint
tilted to show the camera the sun's glint), a small emissive panel of radiance 8, and point,
spot and directional lights.
Run from anywhere; the files land beside this script.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
CAMERA_POSITION = [0, 1.6, 4.2]
SUN = [-1, -2, -0.5]  # the way the directional light travels


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


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def mirror_board(center, half, camera, light_direction):
    """A square quad at `center` tilted so that the camera sees light arriving along
    `light_direction` reflected at its centre: a glint of the sun, which a smooth lobe must not
    show (a delta light meets a delta lobe with probability 0) but a near-delta one shows at
    thousands of times the light's radiance."""
    to_camera = normalize([c - p for c, p in zip(camera, center)])
    to_light = normalize([-c for c in light_direction])
    n = normalize([a + b for a, b in zip(to_camera, to_light)])
    u = normalize(cross(n, [0, 1, 0]))
    v = cross(n, u)
    corner = lambda su, sv: [round(p + half * (su * a + sv * b), 6)
                             for p, a, b in zip(center, u, v)]
    # Counter-clockwise seen from the camera, so the front face looks at it.
    return [corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)]


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
        # Car paint: a mirror-smooth clear coat over a rough base.
        "car_paint": {"type": "principled", "base_color": [0.7, 0.05, 0.05], "roughness": 0.5,
                      "clearcoat": 1, "clearcoat_roughness": 0},
        "panel": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [8, 8, 8]},
    }
    shapes = [
        {"type": "quad", "name": "floor", "material": "floor",
         "vertices": [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]},
        {"type": "quad", "name": "panel", "material": "panel",
         "vertices": [[-0.3, 2.5, -0.3], [0.3, 2.5, -0.3], [0.3, 2.5, 0.3], [-0.3, 2.5, 0.3]]},
    ]
    names = ["gold", "glass", "thin_glass", "plastic", "chrome", "lambert", "mirror",
             "dielectric", "glossy", "car_paint"]
    for k, name in enumerate(names):
        x = -2.0 + 1.0 * (k % 5)
        z = -0.6 + 1.2 * (k // 5)
        shapes.append(sphere(name, name, [x, 0.45, z], 0.45))
    shapes.append({"type": "quad", "name": "lacquered_board", "material": "car_paint",
                   "vertices": mirror_board([1.0, 0.6, 2.0], 0.3, CAMERA_POSITION, SUN)})
    lights = [
        {"type": "point", "position": [1.5, 2.0, 1.5], "intensity": 4},
        {"type": "spot", "position": [-1.5, 2.2, 1.8], "direction": [0.5, -1, -0.8],
         "intensity": 6, "outer_angle_deg": 40, "inner_angle_deg": 30},
        {"type": "directional", "direction": SUN, "irradiance": 2},
    ]
    camera = {"position": CAMERA_POSITION, "look_at": [0, 0.4, 0], "up": [0, 1, 0],
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
