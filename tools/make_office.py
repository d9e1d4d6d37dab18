#!/usr/bin/python3
"""Writes an office floor for the radiosity benchmark (issue 33; tools/radiosity_bench.sh).

A grid of rooms (4 m x 5 m, 3 m high) with thin walls: a door in every wall between two rooms,
a window opening in every outer wall; in each room four desks with chairs, a shelf, two
emissive ceiling panels, and in every eighth room a desk lamp (a point light). Everything is
lambert, lit by emission and point lights, so `--method radiosity` takes it. The camera stands
in the first room's corner.

--triangles N sets the size: about N / 5000 rooms (at least 1), and the floors, ceilings and
walls are tessellated into squares of the side that brings the total nearest N (furniture boxes
stay 10 or 12 triangles). The actual count is printed. Meshes are binary little-endian PLY
files (compact, read by the loader without a material of their own), one per material, next to
OUT/office.json; lamps are quads in the JSON.

Deterministic: numpy's PCG64 with a fixed seed jitters the furniture; the same arguments give
the same bytes. Needs Debian's python3 and python3-numpy:

    /usr/bin/python3 tools/make_office.py --triangles 10000 --out DIR [--resolution 256]
"""

import argparse
import json
import math
import pathlib

import numpy as np

SEED = 33
ROOM_W, ROOM_D, HEIGHT = 4.0, 5.0, 3.0  # x, z, y (m)
TRIANGLES_PER_ROOM = 5000
DOOR = (0.6, 1.5, 0.0, 2.1)  # along the wall from its start (u0, u1), then height (v0, v1)
WINDOW_WIDTH, WINDOW_V = 1.6, (0.9, 2.1)
LAMP_HALF = 0.3  # ceiling panels 0.6 m square, 1 cm below the ceiling
LAMP_NITS = 3000.0
DESK_LAMP_CD = 100.0
POINT_LIGHT_EVERY = 8  # rooms

MATERIALS = {
    "floor": {"type": "lambert", "reflectance": [0.35, 0.3, 0.25]},
    "ceiling": {"type": "lambert", "reflectance": [0.8, 0.8, 0.8]},
    "wall": {"type": "lambert", "reflectance": [0.7, 0.68, 0.62]},
    "desk": {"type": "lambert", "reflectance": [0.55, 0.4, 0.25]},
    "chair": {"type": "lambert", "reflectance": [0.15, 0.2, 0.35]},
    "shelf": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]},
    # Black: the panel's back faces the ceiling 1 cm away (as the Cornell box's light).
    "lamp": {"type": "lambert", "reflectance": [0, 0, 0], "luminance_nits": LAMP_NITS,
             "temperature_k": 4000},
}


def breaks(length, step, cuts):
    """Uniform divisions of [0, length] at most `step` apart, plus the openings' edges."""
    n = max(1, math.ceil(length / step - 1e-9))
    return np.unique(np.round(np.concatenate([np.linspace(0, length, n + 1), cuts]), 9))


class Surface:
    """A rectangle origin + u du + v dv, u in [0, length], v in [0, height], cut into a grid
    of squares with rectangular holes (u0, u1, v0, v1); its front face is du x dv."""

    def __init__(self, origin, du, dv, length, height, holes=()):
        self.origin, self.du, self.dv = (np.array(x, float) for x in (origin, du, dv))
        self.length, self.height, self.holes = length, height, list(holes)

    def _grid(self, step):
        ub = breaks(self.length, step, [c for h in self.holes for c in h[:2]])
        vb = breaks(self.height, step, [c for h in self.holes for c in h[2:]])
        uc, vc = np.meshgrid((ub[:-1] + ub[1:]) / 2, (vb[:-1] + vb[1:]) / 2, indexing="ij")
        keep = np.ones(uc.shape, bool)
        for u0, u1, v0, v1 in self.holes:
            keep &= ~((uc > u0) & (uc < u1) & (vc > v0) & (vc < v1))
        return ub, vb, keep

    def triangles(self, step):
        return 2 * int(self._grid(step)[2].sum())

    def mesh(self, step):
        ub, vb, keep = self._grid(step)
        # Only the grid points some kept cell uses, numbered in (u, v) order.
        used = np.zeros((len(ub), len(vb)), bool)
        for di in (0, 1):
            for dj in (0, 1):
                used[di:len(ub) - 1 + di, dj:len(vb) - 1 + dj] |= keep
        index = np.cumsum(used.ravel()).reshape(used.shape) - 1
        iu, iv = np.nonzero(used)
        vertices = self.origin + ub[iu, None] * self.du + vb[iv, None] * self.dv
        i, j = np.nonzero(keep)
        a, b, c, d = index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]
        faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        return vertices, faces


# Corners of a unit box's faces, counter-clockwise seen from outside; the bottom (-y) first.
BOX_FACES = [
    [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)],
    [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)],
    [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)],
    [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)],
    [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)],
    [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
]


def box(lo, hi, on_floor):
    """An axis-aligned box's vertices and faces; one standing on the floor has no bottom."""
    corners = {(x, y, z): k for k, (x, y, z) in enumerate(np.ndindex(2, 2, 2))}
    lo, hi = np.array(lo, float), np.array(hi, float)
    vertices = np.array([np.where(np.array(c) == 1, hi, lo) for c in corners])
    faces = []
    for quad in BOX_FACES[1 if on_floor else 0:]:
        a, b, c, d = (corners[p] for p in quad)
        faces += [(a, b, c), (a, c, d)]
    return vertices, np.array(faces)


class Office:
    def __init__(self, triangles):
        rooms = max(1, round(triangles / TRIANGLES_PER_ROOM))
        self.nx = max(1, round(math.sqrt(rooms)))
        self.nz = max(1, round(rooms / self.nx))
        self.rng = np.random.default_rng(SEED)
        self.surfaces = {"floor": [], "ceiling": [], "wall": []}
        self.boxes = {"desk": [], "chair": [], "shelf": []}
        self.lamps, self.point_lights = [], []
        for i in range(self.nx):
            for j in range(self.nz):
                self.room(i, j)
        self.walls()

    def room(self, i, j):
        x0, z0 = i * ROOM_W, j * ROOM_D
        # Floor up (+x by -z), ceiling down (+x by +z).
        self.surfaces["floor"].append(
            Surface((x0, 0, z0 + ROOM_D), (1, 0, 0), (0, 0, -1), ROOM_W, ROOM_D))
        self.surfaces["ceiling"].append(
            Surface((x0, HEIGHT, z0), (1, 0, 0), (0, 0, 1), ROOM_W, ROOM_D))
        for k, (cx, cz) in enumerate((a, b) for b in (0.35, 0.65) for a in (0.28, 0.72)):
            x, z = x0 + cx * ROOM_W, z0 + cz * ROOM_D
            x, z = x + self.rng.uniform(-0.1, 0.1), z + self.rng.uniform(-0.1, 0.1)
            self.boxes["desk"] += [
                ((x - 0.6, 0.72, z - 0.35), (x + 0.6, 0.75, z + 0.35), False),
                ((x - 0.6, 0, z - 0.35), (x - 0.57, 0.72, z + 0.35), True),
                ((x + 0.57, 0, z - 0.35), (x + 0.6, 0.72, z + 0.35), True),
            ]
            cx = x + self.rng.uniform(-0.2, 0.2)
            cz = z + 0.6 + self.rng.uniform(-0.05, 0.1)
            self.boxes["chair"] += [
                ((cx - 0.025, 0, cz - 0.025), (cx + 0.025, 0.42, cz + 0.025), True),
                ((cx - 0.225, 0.42, cz - 0.225), (cx + 0.225, 0.47, cz + 0.225), False),
                ((cx - 0.225, 0.47, cz + 0.175), (cx + 0.225, 0.95, cz + 0.225), False),
            ]
            if k == 0 and (i * self.nz + j) % POINT_LIGHT_EVERY == 0:
                self.point_lights.append((x - 0.4, 1.1, z - 0.2))
        # Along the back wall, clear of its door.
        self.boxes["shelf"].append(
            ((x0 + 1.8, 0, z0 + ROOM_D - 0.4), (x0 + 3.4, 1.8, z0 + ROOM_D - 0.01), True))
        y = HEIGHT - 0.01
        for cz in (0.3, 0.7):
            x, z = x0 + 0.5 * ROOM_W, z0 + cz * ROOM_D
            # Counter-clockwise seen from below: the front (emitting) face looks down.
            h = LAMP_HALF
            self.lamps.append([[x - h, y, z - h], [x + h, y, z - h], [x + h, y, z + h],
                               [x - h, y, z + h]])

    def walls(self):
        """Walls of constant x (along +z), then of constant z (along +x): a window in the outer
        ones, a door in those between two rooms."""
        size, count = (ROOM_W, ROOM_D), (self.nx, self.nz)
        for a, along in ((0, (0, 0, 1)), (1, (1, 0, 0))):  # a: the axis (x, z) walls cut
            length = size[1 - a]
            window = ((length - WINDOW_WIDTH) / 2, (length + WINDOW_WIDTH) / 2) + WINDOW_V
            for k in range(count[a] + 1):
                for m in range(count[1 - a]):
                    xz = [0.0, 0.0]
                    xz[a], xz[1 - a] = k * size[a], m * size[1 - a]
                    self.surfaces["wall"].append(Surface(
                        (xz[0], 0, xz[1]), along, (0, 1, 0), length, HEIGHT,
                        [window if k in (0, count[a]) else DOOR]))

    def box_triangles(self):
        return sum(10 if f else 12 for boxes in self.boxes.values() for _, _, f in boxes)

    def surface_triangles(self, step):
        return sum(s.triangles(step) for group in self.surfaces.values() for s in group)

    def step_for(self, target):
        """The tessellation step whose total is nearest the target (the count falls with it)."""
        fixed = self.box_triangles() + 2 * len(self.lamps)
        area = sum(s.length * s.height for group in self.surfaces.values() for s in group)
        guess = math.sqrt(area / max(1, (target - fixed) / 2))
        lo, hi = guess / 4, min(guess * 4, HEIGHT)  # count(lo) > target >= count(hi), nearly
        for _ in range(40):
            mid = math.sqrt(lo * hi)
            if self.surface_triangles(mid) + fixed > target:
                lo = mid
            else:
                hi = mid
        return min((lo, hi), key=lambda s: abs(self.surface_triangles(s) + fixed - target))


def merge(parts):
    vertices, faces, offset = [], [], 0
    for v, f in parts:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(faces)


def write_ply(path, vertices, faces):
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"], face["i"] = 3, faces
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(vertices.astype("<f4").tobytes())
        f.write(face.tobytes())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--triangles", type=int, default=10000, help="target triangle count")
    parser.add_argument("--out", required=True, help="folder for office.json and its meshes")
    parser.add_argument("--resolution", type=int, default=256, help="camera resolution N x N")
    args = parser.parse_args()
    if args.triangles < 1000:
        parser.error("--triangles: at least 1000 (one room's furniture and lamps alone are ~370)")
    office = Office(args.triangles)
    step = office.step_for(args.triangles)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    shapes, counts = [], {}
    for name, group in list(office.surfaces.items()) + list(office.boxes.items()):
        parts = [s.mesh(step) for s in group] if name in office.surfaces else \
            [box(lo, hi, f) for lo, hi, f in group]
        vertices, faces = merge(parts)
        write_ply(out / f"{name}.ply", vertices, faces)
        counts[name] = len(faces)
        shapes.append({"type": "mesh", "name": name, "material": name, "file": f"{name}.ply"})
    shapes += [{"type": "quad", "name": f"lamp {k}", "material": "lamp", "vertices": quad}
               for k, quad in enumerate(office.lamps)]
    counts["lamp"] = 2 * len(office.lamps)
    scene = {
        "version": 1,
        "camera": {"position": [0.9 * ROOM_W, 1.6, 0.9 * ROOM_D], "look_at": [0.3, 0.9, 0.6],
                   "fov_y_deg": 70, "resolution": [args.resolution, args.resolution]},
        "materials": MATERIALS,
        "shapes": shapes,
        "lights": [{"type": "point", "position": list(p), "intensity_cd": DESK_LAMP_CD,
                    "temperature_k": 3000} for p in office.point_lights],
    }
    (out / "office.json").write_text(json.dumps(scene, indent=1) + "\n")
    total = sum(counts.values())
    print(f"office: {office.nx * office.nz} rooms ({office.nx} x {office.nz}), step {step:.4g} m, "
          f"{total} triangles (" + ", ".join(f"{k} {v}" for k, v in counts.items()) +
          f"), {len(office.lamps)} ceiling panels, {len(office.point_lights)} point lights"
          f" -> {out / 'office.json'}")


if __name__ == "__main__":
    main()
