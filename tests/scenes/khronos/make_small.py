"""Copies Khronos glTF sample assets into tests/scenes/khronos, small enough for CI.

Run with Blender's Python (Debian's `blender`; it reads and writes PNG and JPEG):

    blender -b --factory-startup --python tests/scenes/khronos/make_small.py -- \
        SAMPLES_DIR tests/scenes/khronos

SAMPLES_DIR holds KhronosGroup/glTF-Sample-Assets' Models/<Name>/ folders (LICENSE.md,
README.md, glTF/ or glTF-Draco/). What changes, and why nothing a renderer sees does:
- textures over 10 KB and over 128 pixels on a side are scaled down to 128 on their longer
  side, same file name and format (48-pixel test renders cannot tell);
- 32-bit index buffers whose indices all fit 16 bits become 16-bit (lossless);
- the .gltf JSON is written without indentation and its buffers repacked, views in order.
LICENSE.md and README.md are copied beside the asset (the README's screenshot, not copied,
becomes a line naming where it is).
"""

import json
import os
import re
import shutil
import struct
import sys
import urllib.parse

import bpy

ASSETS = {
    "AlphaBlendModeTest": "glTF",
    "AttenuationTest": "glTF",
    "Cameras": "glTF",
    "ClearCoatTest": "glTF",
    "DamagedHelmet": "glTF",
    "EmissiveStrengthTest": "glTF",
    "LightsPunctualLamp": "glTF",
    "MetalRoughSpheresNoTextures": "glTF",
    "MultiUVTest": "glTF",
    "NegativeScaleTest": "glTF",
    "NormalTangentMirrorTest": "glTF",
    "OrientationTest": "glTF",
    "SpecularTest": "glTF",
    "TextureCoordinateTest": "glTF",
    "TextureSettingsTest": "glTF",
    "TextureTransformTest": "glTF",
    "TransmissionTest": "glTF",
    "UnlitTest": "glTF",
    "VertexColorTest": "glTF",
    "WaterBottle": "glTF-Draco",
}
MAX_SIDE = 128
SMALL_FILE = 10 * 1024
UINT32, UINT16 = 5125, 5123


def narrow_indices(gltf, buffers):
    """Views read only as uint32 indices below 65536 become uint16; returns each view's bytes."""
    views = []
    for view in gltf["bufferViews"]:
        data = buffers[view.get("buffer", 0)]
        start = view.get("byteOffset", 0)
        views.append(bytearray(data[start : start + view["byteLength"]]))
    readers = {}
    for accessor in gltf["accessors"]:
        if "bufferView" in accessor:
            readers.setdefault(accessor["bufferView"], []).append(accessor)
    for index, accessors in readers.items():
        view = gltf["bufferViews"][index]
        if "byteStride" in view or any(
            a["componentType"] != UINT32 or a["type"] != "SCALAR" for a in accessors
        ):
            continue
        words = struct.unpack("<%dI" % (len(views[index]) // 4), views[index])
        if max(words, default=0) > 0xFFFF:
            continue
        views[index] = bytearray(struct.pack("<%dH" % len(words), *words))
        view["byteLength"] = len(views[index])
        for a in accessors:
            a["componentType"] = UINT16
            a["byteOffset"] = a.get("byteOffset", 0) // 2
    return views


def repack(gltf, src, dst):
    buffers = []
    for buffer in gltf["buffers"]:
        with open(os.path.join(src, urllib.parse.unquote(buffer["uri"])), "rb") as f:
            buffers.append(f.read())
    views = narrow_indices(gltf, buffers)
    packed = [bytearray() for _ in buffers]
    for view, data in zip(gltf["bufferViews"], views):
        out = packed[view.get("buffer", 0)]
        out.extend(b"\0" * (-len(out) % 4))
        view["byteOffset"] = len(out)
        out.extend(data)
    for buffer, data in zip(gltf["buffers"], packed):
        buffer["byteLength"] = len(data)
        with open(os.path.join(dst, urllib.parse.unquote(buffer["uri"])), "wb") as f:
            f.write(data)


def copy_image(src_path, dst_path):
    os.makedirs(os.path.dirname(dst_path), exist_ok=True)
    image = bpy.data.images.load(src_path)
    width, height = image.size
    if max(width, height) <= MAX_SIDE or os.path.getsize(src_path) <= SMALL_FILE:
        shutil.copyfile(src_path, dst_path)
    else:
        scale = MAX_SIDE / max(width, height)
        image.scale(max(1, round(width * scale)), max(1, round(height * scale)))
        image.filepath_raw = dst_path
        image.save()
    bpy.data.images.remove(image)


def copy_asset(name, variant, samples, out):
    src = os.path.join(samples, name, variant)
    dst = os.path.join(out, name)
    shutil.rmtree(dst, ignore_errors=True)
    os.makedirs(dst)
    shutil.copyfile(os.path.join(samples, name, "LICENSE.md"), os.path.join(dst, "LICENSE.md"))
    with open(os.path.join(samples, name, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    where = "(screenshot in KhronosGroup/glTF-Sample-Assets, Models/%s)" % name
    with open(os.path.join(dst, "README.md"), "w", encoding="utf-8") as f:
        f.write(re.sub(r"!\[[^\]]*\]\(screenshot/[^)]*\)", where, readme))
    with open(os.path.join(src, name + ".gltf"), encoding="utf-8") as f:
        gltf = json.load(f)
    repack(gltf, src, dst)
    for image in gltf.get("images", []):
        if "uri" in image and not image["uri"].startswith("data:"):
            uri = urllib.parse.unquote(image["uri"])
            copy_image(os.path.join(src, uri), os.path.join(dst, uri))
    with open(os.path.join(dst, name + ".gltf"), "w", encoding="utf-8") as f:
        json.dump(gltf, f, separators=(",", ":"), ensure_ascii=False)
        f.write("\n")


def main():
    samples, out = sys.argv[sys.argv.index("--") + 1 :][:2]
    for name, variant in ASSETS.items():
        copy_asset(name, variant, samples, out)
        print("copied", name)


main()
