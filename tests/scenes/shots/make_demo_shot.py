#!/usr/bin/env python3
"""Writes demo_shot.gltf (and copies checker.png beside it): tests/scenes/gltf_demo/demo.gltf with
its two spheres animated over 10 s (240 frames at 24 fps), for tools/shot_bench.sh. The gold
sphere bounces 1.2 high once a second, the glass sphere rolls 2 back and returns over the 10 s;
LINEAR keys every 1/8 s. Stdlib only; run from anywhere."""
import base64
import json
import math
import os
import shutil
import struct

SECONDS, KEYS_PER_SECOND = 10.0, 8


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    demo = os.path.join(here, "..", "gltf_demo")
    with open(os.path.join(demo, "demo.gltf")) as f:
        gltf = json.load(f)
    nodes = {n.get("name"): i for i, n in enumerate(gltf["nodes"])}
    gold, glass = nodes["Gold"], nodes["Glass"]
    gold_at, glass_at = gltf["nodes"][gold]["translation"], gltf["nodes"][glass]["translation"]

    times = [k / KEYS_PER_SECOND for k in range(int(SECONDS * KEYS_PER_SECOND) + 1)]
    bounce = [(gold_at[0], gold_at[1] + 1.2 * abs(math.sin(math.pi * t)), gold_at[2])
              for t in times]
    roll = [(glass_at[0], glass_at[1], glass_at[2] - 2.0 * math.sin(math.pi * t / SECONDS) ** 2)
            for t in times]

    data = bytearray()
    first_view = len(gltf["bufferViews"])
    for fmt, rows in (("<f", [(t,) for t in times]), ("<3f", bounce), ("<3f", roll)):
        start = len(data)
        for row in rows:
            data += struct.pack(fmt, *row)
        gltf["bufferViews"].append({"buffer": len(gltf["buffers"]), "byteOffset": start,
                                    "byteLength": len(data) - start})
    gltf["buffers"].append({"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                            + base64.b64encode(bytes(data)).decode("ascii")})
    first = len(gltf["accessors"])
    gltf["accessors"] += [
        {"bufferView": first_view, "componentType": 5126, "count": len(times), "type": "SCALAR",
         "min": [times[0]], "max": [times[-1]]},
        {"bufferView": first_view + 1, "componentType": 5126, "count": len(times), "type": "VEC3"},
        {"bufferView": first_view + 2, "componentType": 5126, "count": len(times), "type": "VEC3"},
    ]
    gltf["animations"] = [{
        "name": "spheres",
        "samplers": [{"input": first, "output": first + 1, "interpolation": "LINEAR"},
                     {"input": first, "output": first + 2, "interpolation": "LINEAR"}],
        "channels": [{"sampler": 0, "target": {"node": gold, "path": "translation"}},
                     {"sampler": 1, "target": {"node": glass, "path": "translation"}}],
    }]
    gltf["asset"]["generator"] = "lightfarm tests/scenes/shots/make_demo_shot.py"
    with open(os.path.join(here, "demo_shot.gltf"), "w") as f:
        json.dump(gltf, f, separators=(",", ":"))
        f.write("\n")
    shutil.copy(os.path.join(demo, "checker.png"), here)


if __name__ == "__main__":
    main()
