#!/usr/bin/env python3
"""Writes a textured UV sphere as plain glTF (sphere.gltf, sphere.bin) and as its
KHR_draco_mesh_compression twins: sphere_draco.gltf (edgebreaker, the encoder's default) and
sphere_draco_sequential.glb (sequential connectivity, -cl 0), compressed by Debian's draco_encoder
(package `draco`) at -qp 14 -qt 12 -qn 10. Each has a camera, a directional light (2000 lux,
about 2.9 W/m^2) and a checker
texture (checker.png), so a render shows positions, normals and UVs. Also the glTF fuzzer's
seeds (tests/fuzz/corpus/gltf_fuzz/draco_*): both twins without the texture, which the fuzzer
cannot read, and with the buffer inside the file. Run from anywhere:
  python3 tests/scenes/draco/make_draco_twins.py
"""
import base64
import json
import math
import os
import struct
import subprocess
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEGMENTS, RINGS = 16, 10
QUANTISATION = ["-qp", "14", "-qt", "12", "-qn", "10"]


def sphere(segments=SEGMENTS, rings=RINGS):
    """Vertices (position, normal, uv) and triangles; every vertex used, no degenerate face."""
    vertices, index = [], {}

    def vertex(ring, seg, u):
        theta, phi = math.pi * ring / rings, 2 * math.pi * u
        n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
        key = (ring, seg)
        if key not in index:
            index[key] = len(vertices)
            vertices.append((n, n, (u, ring / rings)))
        return index[key]

    triangles = []
    for ring in range(rings):
        for seg in range(segments):
            u0, u1 = seg / segments, (seg + 1) / segments
            if ring == 0:  # the north pole: one vertex per segment, at its middle's u
                triangles.append((vertex(0, seg, (u0 + u1) / 2), vertex(1, seg, u0),
                                  vertex(1, seg + 1, u1)))
            elif ring == rings - 1:
                triangles.append((vertex(ring, seg, u0), vertex(rings, seg, (u0 + u1) / 2),
                                  vertex(ring, seg + 1, u1)))
            else:
                a, b = vertex(ring, seg, u0), vertex(ring, seg + 1, u1)
                c, d = vertex(ring + 1, seg, u0), vertex(ring + 1, seg + 1, u1)
                triangles += [(a, c, d), (a, d, b)]
    return vertices, triangles


def checker_png(size=8):
    rows = b""
    for y in range(size):
        rows += b"\0" + b"".join(
            bytes((230, 40, 30) if (x + y) % 2 else (240, 240, 240)) for x in range(size))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def scene_json(extensions_required):
    """Everything but meshes, accessors, bufferViews and buffers."""
    j = {
        "asset": {"version": "2.0", "generator": "tests/scenes/draco/make_draco_twins.py"},
        "extensionsUsed": ["KHR_lights_punctual"] + extensions_required,
        "extensionsRequired": extensions_required,
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "name": "sphere"},
            {"camera": 0, "translation": [0, 0.4, 3.2], "rotation": [-0.0622, 0, 0, 0.9981]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}},
             "rotation": [-0.2588190, 0, 0, 0.9659258]},  # 30 degrees down from -z
        ],
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.7, "aspectRatio": 1.0, "znear": 0.1}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional",
                                                            "intensity": 2000.0}]}},
        "materials": [{"name": "checker", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 0.6}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": [{"uri": "checker.png"}],
    }
    if not extensions_required:
        del j["extensionsRequired"]
    return j


def accessors(vertices, triangles, indices_view, views):
    """POSITION, NORMAL, TEXCOORD_0 and indices accessors; views[k] is the k-th attribute's
    bufferView (None: the Draco bitstream holds it)."""
    n = len(vertices)
    out = []
    for k, kind in enumerate(("VEC3", "VEC3", "VEC2")):
        a = {"componentType": 5126, "count": n, "type": kind}
        if k == 0:
            a["min"] = [min(v[0][i] for v in vertices) for i in range(3)]
            a["max"] = [max(v[0][i] for v in vertices) for i in range(3)]
        if views[k] is not None:
            a["bufferView"] = views[k]
        out.append(a)
    indices = {"componentType": 5125, "count": 3 * len(triangles), "type": "SCALAR"}
    if indices_view is not None:
        indices["bufferView"] = indices_view
    out.append(indices)
    return out


def primitive(extension=None):
    p = {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
         "material": 0}
    if extension:
        p["extensions"] = {"KHR_draco_mesh_compression": extension}
    return p


def write_plain(vertices, triangles):
    blobs = [b"".join(struct.pack("<3f", *v[0]) for v in vertices),
             b"".join(struct.pack("<3f", *v[1]) for v in vertices),
             b"".join(struct.pack("<2f", *v[2]) for v in vertices),
             b"".join(struct.pack("<3I", *t) for t in triangles)]
    j = scene_json([])
    j["bufferViews"], offset = [], 0
    for blob in blobs:
        j["bufferViews"].append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob)})
        offset += len(blob)
    j["accessors"] = accessors(vertices, triangles, 3, [0, 1, 2])
    j["meshes"] = [{"name": "sphere", "primitives": [primitive()]}]
    j["buffers"] = [{"uri": "sphere.bin", "byteLength": offset}]
    with open(os.path.join(HERE, "sphere.bin"), "wb") as f:
        f.write(b"".join(blobs))
    with open(os.path.join(HERE, "sphere.gltf"), "w") as f:
        json.dump(j, f, indent=1)


def encode(vertices, triangles, level):
    with tempfile.TemporaryDirectory() as tmp:
        obj = os.path.join(tmp, "sphere.obj")
        with open(obj, "w") as f:
            for p, n, uv in vertices:
                f.write("v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\nvt %.9g %.9g\n" % (*p, *n, *uv))
            for t in triangles:
                f.write("f %s\n" % " ".join("%d/%d/%d" % (i + 1, i + 1, i + 1) for i in t))
        drc = os.path.join(tmp, "sphere.drc")
        subprocess.run(["draco_encoder", "-i", obj, "-o", drc, "-cl", str(level)] + QUANTISATION,
                       check=True, stdout=subprocess.DEVNULL)
        with open(drc, "rb") as f:
            return f.read()


def draco_json(vertices, triangles, stream_bytes, uri):
    j = scene_json(["KHR_draco_mesh_compression"])
    j["bufferViews"] = [{"buffer": 0, "byteOffset": 0, "byteLength": stream_bytes}]
    j["accessors"] = accessors(vertices, triangles, None, [None, None, None])
    # draco_encoder numbers an OBJ's attributes position, texture coordinate, normal.
    j["meshes"] = [{"name": "sphere", "primitives": [primitive(
        {"bufferView": 0, "attributes": {"POSITION": 0, "TEXCOORD_0": 1, "NORMAL": 2}})]}]
    j["buffers"] = [{"byteLength": stream_bytes}]
    if uri:
        j["buffers"][0]["uri"] = uri
    return j


def write_draco_gltf(vertices, triangles):
    stream = encode(vertices, triangles, 7)
    with open(os.path.join(HERE, "sphere_draco.bin"), "wb") as f:
        f.write(stream)
    with open(os.path.join(HERE, "sphere_draco.gltf"), "w") as f:
        json.dump(draco_json(vertices, triangles, len(stream), "sphere_draco.bin"), f, indent=1)


def glb(j, stream):
    text = json.dumps(j).encode()
    text += b" " * (-len(text) % 4)
    binary = stream + b"\0" * (-len(stream) % 4)
    glb = (b"glTF" + struct.pack("<II", 2, 12 + 8 + len(text) + 8 + len(binary)) +
           struct.pack("<I", len(text)) + b"JSON" + text +
           struct.pack("<I", len(binary)) + b"BIN\0" + binary)
    return glb


def write_draco_glb(vertices, triangles):
    stream = encode(vertices, triangles, 0)
    with open(os.path.join(HERE, "sphere_draco_sequential.glb"), "wb") as f:
        f.write(glb(draco_json(vertices, triangles, len(stream), None), stream))


def write_fuzz_seeds(vertices, triangles):
    """The fuzz target's first byte picks .gltf (even) or .glb (odd)."""
    corpus = os.path.join(HERE, "..", "..", "fuzz", "corpus", "gltf_fuzz")
    for level, name in ((0, "draco_sequential.glb"), (7, "draco_edgebreaker.gltf")):
        stream = encode(vertices, triangles, level)
        j = draco_json(vertices, triangles, len(stream), None)
        for key in ("materials", "textures", "samplers", "images"):
            del j[key]
        del j["meshes"][0]["primitives"][0]["material"]
        if name.endswith(".glb"):
            data = b"\x01" + glb(j, stream)
        else:
            j["buffers"][0]["uri"] = ("data:application/octet-stream;base64," +
                                      base64.b64encode(stream).decode())
            data = b"\x00" + json.dumps(j).encode()
        with open(os.path.join(corpus, name), "wb") as f:
            f.write(data)


def main():
    vertices, triangles = sphere()
    with open(os.path.join(HERE, "checker.png"), "wb") as f:
        f.write(checker_png())
    write_plain(vertices, triangles)
    write_draco_gltf(vertices, triangles)
    write_draco_glb(vertices, triangles)
    write_fuzz_seeds(vertices, triangles)
    print("%d vertices, %d triangles" % (len(vertices), len(triangles)))


if __name__ == "__main__":
    main()
