"""Bakes a small Mantaflow fire in Blender (headless) and writes one frame of its OpenVDB cache
with a lightfarm scene that renders it (tests/scenes/media/blender_fire.vdb and .json):

    blender -b --factory-startup --python tools/make_blender_smoke.py -- \
        [OUTDIR] [--resolution N] [--frame F]

OUTDIR defaults to tests/scenes/media, N to 32 (the domain's Resolution Divisions), F to 50. The
scene is what Object > Quick Effects > Quick Smoke (style Fire) makes of a 0.5 m cube, with the
domain's cache settings left at Blender 3.4's defaults (OpenVDB, Blosc, Half precision, no
noise) except its size: the domain is 2 x 2 x 4 m (Blender's x, y, z) with its floor at z = 0,
so that for an even N the cells are cubes that fill it exactly. The cache is baked into a temporary
directory and frame F's data file (cache/data/fluid_data_00FF.vdb) is copied as it is.

The medium's transform follows from the domain: the cache stores cell (i, j, k) of the domain
at OpenVDB index (i, j, k) with a plain voxel-size transform (no rotation, no translation: the
domain's placement is not in the file), while Mantaflow's values sit at cell centres, so in
Blender's world the value (i, j, k) is at domain_min + (i + 1/2, j + 1/2, k + 1/2) * dx. The
scene turns Blender's z-up into lightfarm's y-up as Blender's glTF exporter does ((x, y, z) ->
(x, z, -y)). Running it again bakes the same voxels (the files differ only in the random UUID
OpenVDB writes into each).
"""

import json
import os
import shutil
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from media_scenes import box_quads, quad  # noqa: E402

DOMAIN_SIZE = (2.0, 2.0, 4.0)  # Blender x, y, z; floor at z = 0
FLOW_SIZE, FLOW_Z = 0.5, 0.35


def parse_args():
    args = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "scenes", "media")
    resolution, frame = 32, 50
    positional = []
    i = 0
    while i < len(args):
        if args[i] in ("--resolution", "--frame") and i + 1 < len(args):
            value = int(args[i + 1])
            if args[i] == "--resolution":
                resolution = value
            else:
                frame = value
            i += 2
        else:
            positional.append(args[i])
            i += 1
    if positional:
        out = positional[0]
    if resolution < 8 or resolution % 2 or frame < 1:
        sys.exit("make_blender_smoke.py: --resolution must be even and at least 8, "
                 "--frame at least 1")
    return os.path.abspath(out), resolution, frame


def build_fire(resolution, frame_end, cache_dir):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_cube_add(size=FLOW_SIZE, location=(0.0, 0.0, FLOW_Z))
    bpy.ops.object.quick_smoke(style="FIRE")
    domain = bpy.data.objects["Smoke Domain"]
    domain.location = (0.0, 0.0, DOMAIN_SIZE[2] / 2)
    domain.scale = tuple(s / 2 for s in DOMAIN_SIZE)  # the default cube spans [-1, 1]
    settings = domain.modifiers["Fluid"].domain_settings
    settings.resolution_max = resolution
    settings.use_noise = False  # Quick Smoke turns it on for fire; the domain's default is off
    settings.cache_directory = cache_dir
    settings.cache_type = "ALL"  # bake_all below; Replay writes the same files frame by frame
    settings.cache_frame_end = frame_end
    bpy.context.scene.frame_end = frame_end
    with bpy.context.temp_override(active_object=domain, object=domain, selected_objects=[domain]):
        if bpy.ops.fluid.bake_all() != {"FINISHED"}:
            sys.exit("make_blender_smoke.py: the bake failed")


def to_y_up(p):
    return [p[0], p[2], -p[1]]


def scene_json(vdb_name, dx):
    half = [s / 2 for s in DOMAIN_SIZE]
    blender_min = [-half[0], -half[1], 0.0]
    blender_max = [half[0], half[1], DOMAIN_SIZE[2]]
    first_value = [c + dx / 2 for c in blender_min]  # index (0, 0, 0): the first cell's centre
    # The domain box in lightfarm's y-up frame: Blender's -y side becomes +z.
    lo = [blender_min[0], blender_min[2], -blender_max[1]]
    hi = [blender_max[0], blender_max[2], -blender_min[1]]
    return {
        "camera": {"position": [0.0, 2.0, 9.0], "look_at": [0.0, 1.6, 0.0], "fov_y_deg": 35.0,
                   "resolution": [96, 144]},
        "media": {
            "fire": {
                # Quick Smoke's Principled Volume: density 5, colour 0.5, absorption colour
                # black, anisotropy 0, blackbody intensity 1 at its default 1000 K.
                "type": "grid", "file": vdb_name, "density_grid": "density",
                "sigma_a": [2.5, 2.5, 2.5], "sigma_s": [2.5, 2.5, 2.5], "scale": 1.0, "g": 0.0,
                "temperature_grid": "temperature", "temperature_scale": 1000.0,
                "transform": {"rotate": {"axis": [1, 0, 0], "angle_deg": -90},
                              "translate": to_y_up(first_value)},
            }
        },
        "materials": {
            "boundary": {"type": "interface"},
            "ground": {"type": "lambert", "reflectance": [0.3, 0.3, 0.3]},
        },
        "shapes": [quad("ground", "ground", [[-6, 0, -6], [-6, 0, 6], [6, 0, 6], [6, 0, -6]])]
        + box_quads("fire domain", "boundary", lo, hi, "fire"),
        "lights": [{"type": "environment", "radiance": [0.02, 0.03, 0.05]}],
    }


def main():
    out, resolution, frame = parse_args()
    os.makedirs(out, exist_ok=True)
    cache_dir = tempfile.mkdtemp(prefix="lightfarm_fire_")
    os.chdir(cache_dir)  # Mantaflow writes waveletNoiseTile.bin into the working directory
    try:
        build_fire(resolution, frame, cache_dir)
        dx = max(DOMAIN_SIZE) / resolution
        cells = [round(s / dx) for s in DOMAIN_SIZE]
        source = os.path.join(cache_dir, "data", f"fluid_data_{frame:04d}.vdb")
        target = os.path.join(out, "blender_fire.vdb")
        shutil.copyfile(source, target)
        with open(os.path.join(out, "blender_fire.json"), "w") as f:
            json.dump(scene_json("blender_fire.vdb", dx), f, indent=1)
            f.write("\n")
        print(f"make_blender_smoke.py: {target}: frame {frame} of a {cells[0]}x{cells[1]}x"
              f"{cells[2]} fire, voxel {dx} m, {os.path.getsize(target)} bytes")
    finally:
        shutil.rmtree(cache_dir, ignore_errors=True)


main()
