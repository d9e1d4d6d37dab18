#!/usr/bin/env python3
"""Writes tests/scenes/many_lights.json: the many-lights scene of the quality benchmark
(tools/quality_bench.sh, docs/convergence.md).

1,000 small square emitters (0.1 x 0.1, facing down, one material) above a 80 x 80 diffuse floor,
at distances from the origin log-uniform in [0.5, 30] and directions in the upper hemisphere
(elevation cosine uniform in [0.1, 1]), so a shading point near the origin has a few bright
near lights among many faint far ones: picking lights by power alone (all equal here) wastes
most shadow rays on lights that contribute nothing, which a light BVH need not.

Deterministic: a fixed seed of Python's Mersenne Twister (random.random() is stable across
Python versions), coordinates rounded to 1e-4. Run from anywhere:

    python3 tools/make_many_lights.py [--count 1000] [--out tests/scenes/many_lights.json]
"""

import argparse
import json
import math
import pathlib
import random

SEED = 14
HALF_SIZE = 0.05  # emitter half-width
MIN_DISTANCE, MAX_DISTANCE = 0.5, 30.0
FLOOR_HALF_SIZE = 40.0


def r4(x):
    return round(x, 4)


def scene(count):
    rng = random.Random(SEED)
    shapes = [{
        "type": "quad", "name": "floor", "material": "floor",
        # Counter-clockwise seen from above: the front face is up.
        "vertices": [[-FLOOR_HALF_SIZE, 0, -FLOOR_HALF_SIZE], [-FLOOR_HALF_SIZE, 0, FLOOR_HALF_SIZE],
                     [FLOOR_HALF_SIZE, 0, FLOOR_HALF_SIZE], [FLOOR_HALF_SIZE, 0, -FLOOR_HALF_SIZE]],
    }]
    for i in range(count):
        distance = MIN_DISTANCE * (MAX_DISTANCE / MIN_DISTANCE) ** rng.random()
        phi = 2 * math.pi * rng.random()
        cos_t = 0.1 + 0.9 * rng.random()
        sin_t = math.sqrt(1 - cos_t * cos_t)
        x, y, z = distance * sin_t * math.cos(phi), distance * cos_t, distance * sin_t * math.sin(phi)
        h = HALF_SIZE
        shapes.append({
            "type": "quad", "name": f"light{i}", "material": "light",
            # Counter-clockwise seen from below: the front (emitting) face is down.
            "vertices": [[r4(x - h), r4(y), r4(z - h)], [r4(x + h), r4(y), r4(z - h)],
                         [r4(x + h), r4(y), r4(z + h)], [r4(x - h), r4(y), r4(z + h)]],
        })
    return {
        "camera": {"position": [0, 1.2, -4], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
                   "fov_y_deg": 50, "resolution": [64, 64]},
        "materials": {
            "floor": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]},
            "light": {"type": "lambert", "reflectance": [0, 0, 0], "emission": [10, 7, 4]},
        },
        "shapes": shapes,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = pathlib.Path(__file__).resolve().parent.parent
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--out", default=str(root / "tests" / "scenes" / "many_lights.json"))
    args = parser.parse_args()
    text = json.dumps(scene(args.count), separators=(",", ":"))
    # One shape per line keeps the file diffable without the size of full indentation.
    text = text.replace(',{"type"', ',\n{"type"')
    pathlib.Path(args.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
