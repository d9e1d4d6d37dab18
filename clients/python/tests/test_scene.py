"""lightfarm.scene_files: which files a scene names, by the names the loader asks for. No server:
files made in a temporary folder. Run with PYTHONPATH=build/python (ctest python_scene_files)."""

import json
import os
import struct
import tempfile
import unittest

import lightfarm


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)


def glb(doc):
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


class SceneFilesTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = os.path.join(self.tmp.name, "scene")

    def tearDown(self):
        self.tmp.cleanup()

    def p(self, *names):
        return os.path.join(self.dir, *names)

    def test_json_scene(self):
        sky = os.path.join(self.tmp.name, "sky.hdr")  # an absolute name
        write(sky, b"sky")
        write(self.p("meshes", "a.obj"), "mtllib a.mtl sub/missing.mtl\nv 0 0 0\n")
        write(self.p("meshes", "a.mtl"),
              "newmtl m\nKd 1 1 1\nmap_Kd -bm 1 ../tex/d.png\nmap_Ke ../tex/d.png\n")
        write(self.p("tex", "d.png"), b"d")
        write(self.p("tex", "c.png"), b"c")
        write(self.p("tex", "n.png"), b"n")
        write(self.p("tex", "e.png"), b"e")
        write(os.path.join(self.tmp.name, "outside", "b.ply"), b"ply")
        write(self.p("models", "m data.bin"), b"bin")
        write(self.p("models", "m.gltf"), json.dumps({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": "m%20data.bin", "byteLength": 3},
                        {"uri": "data:application/octet-stream;base64,AAAA"}],
            "images": [{"uri": "../tex/e.png"}, {"bufferView": 0, "mimeType": "image/png"}]}))
        write(self.p("scene.json"), json.dumps({
            "camera": {"position": [0, 0, 0], "look_at": [0, 0, 1]},
            "materials": {
                "a": {"type": "principled", "base_color_texture": "tex/c.png",
                      "normal_texture": {"file": "tex/n.png", "wrap": "clamp"}}},
            "shapes": [
                {"type": "mesh", "file": "./meshes/a.obj"},
                {"type": "mesh", "file": "../outside/b.ply", "material": "a"},
                {"type": "gltf", "file": "models/m.gltf"}],
            "lights": [{"type": "environment", "file": sky}]}))
        text, files = lightfarm.scene_files(self.p("scene.json"))
        self.assertTrue(text.startswith(b"{"))
        names = dict(files)
        self.assertEqual(sorted(names), sorted([
            "./meshes/a.obj", "meshes/a.mtl", "tex/d.png", "tex/c.png", "tex/n.png",
            "../outside/b.ply", "models/m.gltf", "models/m data.bin", "tex/e.png", sky]))
        self.assertEqual(names["models/m data.bin"], b"bin")
        self.assertEqual(names[sky], b"sky")

    def test_media_grid_files(self):
        write(self.p("cache", "smoke.vdb"), b"vdb")
        write(self.p("scene.json"), json.dumps({
            "camera": {"position": [0, 0, 0], "look_at": [0, 0, 1], "medium": "fog"},
            "media": {"fog": {"type": "homogeneous", "sigma_s": [1, 1, 1]},
                      "smoke": {"type": "grid", "file": "cache/smoke.vdb"}},
            "shapes": []}))
        _, files = lightfarm.scene_files(self.p("scene.json"))
        self.assertEqual(dict(files), {"cache/smoke.vdb": b"vdb"})

    def test_gltf_and_glb_scenes(self):
        write(self.p("buf.bin"), b"b")
        write(self.p("img", "i.png"), b"i")
        write(self.p("demo.gltf"), json.dumps({
            "asset": {"version": "2.0"}, "buffers": [{"uri": "buf.bin"}],
            "images": [{"uri": "img/i.png"}]}))
        self.assertEqual([n for n, _ in lightfarm.scene_files(self.p("demo.gltf"))[1]],
                         ["buf.bin", "img/i.png"])
        write(self.p("demo.glb"), glb({"asset": {"version": "2.0"},
                                       "buffers": [{"byteLength": 0}, {"uri": "buf.bin"}],
                                       "images": [{"uri": "./img/../img/i.png"}]}))
        self.assertEqual([n for n, _ in lightfarm.scene_files(self.p("demo.glb"))[1]],
                         ["buf.bin", "img/i.png"])
        # A JSON scene including the GLB from another folder: names relative to its folder.
        write(self.p("top", "scene.json"), json.dumps(
            {"shapes": [{"type": "gltf", "file": "../demo.glb"}]}))
        self.assertEqual([n for n, _ in lightfarm.scene_files(self.p("top", "scene.json"))[1]],
                         ["../buf.bin", "../demo.glb", "../img/i.png"])

    def test_a_named_file_that_cannot_be_read(self):
        write(self.p("scene.json"), json.dumps({"shapes": [{"type": "mesh", "file": "no.obj"}]}))
        with self.assertRaises(lightfarm.InvalidArgument) as caught:
            lightfarm.scene_files(self.p("scene.json"))
        self.assertIn("shapes[0].file \"no.obj\"", caught.exception.message)
        with self.assertRaises(lightfarm.InvalidArgument):
            lightfarm.scene_files(self.p("absent.json"))

    def test_malformed_json_is_left_to_the_server(self):
        write(self.p("bad.json"), '{"shapes": [')
        text, files = lightfarm.scene_files(self.p("bad.json"))
        self.assertEqual((text, files), (b'{"shapes": [', []))


if __name__ == "__main__":
    unittest.main()
