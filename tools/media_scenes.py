"""Writes lightfarm's participating-media scenes (the JSON "media" format of issue 32):

    python3 tools/media_scenes.py tests [OUTDIR]        the small test scenes (default
                                                        tests/scenes/media): slab, furnace,
                                                        furnace_albedo, cornell_fog, spot_sphere
    python3 tools/media_scenes.py bench OUTDIR GRID.vdb  the benchmark's scenes around a 2 m grid
                                                        centred on the origin (tools/media_bench.sh)

tests/scenes/media/README.md says what each scene shows and the values the tests expect.
"""

import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def quad(name, material, corners, interior=None):
    shape = {"type": "quad", "name": name, "material": material, "vertices": corners}
    if interior:
        shape["interior"] = interior
    return shape


def box_quads(name, material, lo, hi, interior=None, inward=False):
    """The six faces of the box [lo, hi], front faces outward (or inward: a room's walls)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = {
        "-x": [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],
        "+x": [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]],
        "-y": [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
        "+y": [[x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]],
        "-z": [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]],
        "+z": [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
    }
    return [quad(f"{name} {side}", material, c[::-1] if inward else c, interior)
            for side, c in faces.items()]


def homogeneous(sigma_a, sigma_s, g=0.0, scale=1.0):
    return {"type": "homogeneous", "sigma_a": sigma_a, "sigma_s": sigma_s, "scale": scale,
            "g": g}


def slab():
    """An emitter of radiance 1 seen head-on through 0.5 m of absorbing medium."""
    return {
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y_deg": 2.0,
                   "resolution": [8, 8]},
        "media": {"slab": homogeneous([0.5, 1.0, 2.0], [0, 0, 0])},
        "materials": {
            "boundary": {"type": "interface"},
            "emitter": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [1, 1, 1]},
        },
        "shapes": [quad("emitter", "emitter", [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]])]
        + box_quads("slab", "boundary", [-1, -1, 0], [1, 1, 0.5], "slab"),
    }


def furnace(sigma_a):
    """A scattering sphere (sigma_s 2) in a uniform environment of radiance 1: with sigma_a 0
    every pixel is 1, with sigma_a 2 (albedo 0.5) tools/media_reference.py gives the image."""
    return {
        "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_y_deg": 40.0,
                   "resolution": [16, 16]},
        "media": {"cloud": homogeneous([sigma_a] * 3, [2.0, 2.0, 2.0], g=0.5)},
        "materials": {"boundary": {"type": "interface"}},
        "shapes": [{"type": "sphere", "name": "cloud", "material": "boundary", "center": [0, 0, 0],
                    "radius": 1.0, "interior": "cloud"}],
        "lights": [{"type": "environment", "radiance": [1, 1, 1]}],
    }


def cornell_fog():
    """The Cornell box, camera and all, inside a box of fog (walls leave rays in the fog)."""
    with open(os.path.join(HERE, "..", "tests", "scenes", "cornell_box.json")) as f:
        scene = json.load(f)
    scene["camera"]["resolution"] = [64, 64]
    scene["camera"]["medium"] = "fog"
    scene["media"] = {"fog": homogeneous([0.1, 0.1, 0.1], [0.8, 0.8, 0.8], g=0.3)}
    scene["materials"]["boundary"] = {"type": "interface"}
    scene["shapes"] += box_quads("fog", "boundary", [-0.05, -0.05, -0.9], [0.61, 0.6, 0.61], "fog")
    return scene


def spot_sphere():
    """A closed grey room with a scattering sphere lit from above by a spot light."""
    return {
        "camera": {"position": [0, 1.0, 1.9], "look_at": [0, 0.7, 0], "fov_y_deg": 50.0,
                   "resolution": [64, 64]},
        "media": {"smoke": homogeneous([0.2, 0.2, 0.2], [4.0, 3.0, 2.0], g=0.6)},
        "materials": {
            "boundary": {"type": "interface"},
            "wall": {"type": "lambert", "reflectance": [0.6, 0.6, 0.6]},
        },
        "shapes": box_quads("room", "wall", [-1, 0, -1], [1, 2, 2], inward=True)
        + [{"type": "sphere", "name": "smoke ball", "material": "boundary",
            "center": [0, 0.7, 0], "radius": 0.4, "interior": "smoke"}],
        "lights": [{"type": "spot", "position": [0, 1.95, 0], "direction": [0, -1, 0],
                    "intensity": [2, 2, 2], "inner_angle_deg": 15, "outer_angle_deg": 25}],
    }


def bench(grid_file, scale):
    """Sun, sky and ground; with scale > 0 the grid's smoke with sigma_t scaled by it."""
    scene = {
        "camera": {"position": [0, 1.3, 5.5], "look_at": [0, 1.0, 0], "fov_y_deg": 40.0,
                   "resolution": [512, 512]},
        "materials": {"ground": {"type": "lambert", "reflectance": [0.4, 0.38, 0.35]}},
        "shapes": [quad("ground", "ground",
                        [[-20, 0, -20], [-20, 0, 20], [20, 0, 20], [20, 0, -20]])],
        "lights": [
            {"type": "directional", "direction": [-1, -2, -1], "irradiance": 3.0,
             "temperature_k": 5800, "angular_diameter_deg": 0.53},
            {"type": "environment", "radiance": [0.25, 0.35, 0.5]},
        ],
    }
    if scale > 0:
        # Albedo 0.9, sigma_t 4 m^-1 at density 1; the 2 m grid (centred on the origin) rests
        # just above the ground.
        scene["media"] = {"smoke": {"type": "grid", "file": grid_file, "density_grid": "density",
                                    "sigma_a": [0.4, 0.4, 0.4], "sigma_s": [3.6, 3.6, 3.6],
                                    "scale": scale, "g": 0.0,
                                    "transform": {"translate": [0, 1.05, 0]}}}
        scene["materials"]["boundary"] = {"type": "interface"}
        scene["shapes"] += box_quads("smoke", "boundary", [-1, 0.05, -1], [1, 2.05, 1], "smoke")
    return scene


def write(path, scene):
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")
    print(path)


def main():
    args = sys.argv[1:]
    if len(args) in (1, 2) and args[0] == "tests":
        out = args[1] if len(args) == 2 else os.path.join(HERE, "..", "tests", "scenes", "media")
        os.makedirs(out, exist_ok=True)
        write(os.path.join(out, "slab.json"), slab())
        write(os.path.join(out, "furnace.json"), furnace(0.0))
        write(os.path.join(out, "furnace_albedo.json"), furnace(2.0))
        write(os.path.join(out, "cornell_fog.json"), cornell_fog())
        write(os.path.join(out, "spot_sphere.json"), spot_sphere())
    elif len(args) == 3 and args[0] == "bench":
        out, grid = args[1], os.path.abspath(args[2])
        os.makedirs(out, exist_ok=True)
        write(os.path.join(out, "clear.json"), bench(grid, 0))
        for scale in (1, 10, 100):
            write(os.path.join(out, f"smoke_{scale}x.json"), bench(grid, scale))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
