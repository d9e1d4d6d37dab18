#!/usr/bin/python3
"""tools/make_office.py: the 10k office of the radiosity benchmark (tools/radiosity_bench.sh) is
written, counted as printed, deterministic, and loads in `lightfarm plan`.

    make_office_test.py BIN_DIR SOURCE_DIR
"""

import json
import pathlib
import re
import subprocess
import sys
import tempfile
import unittest

BIN_DIR, SOURCE_DIR = (pathlib.Path(a) for a in sys.argv[1:3])
GENERATOR = SOURCE_DIR / "tools" / "make_office.py"


def ply_faces(path):
    """The face count of a PLY header; every face must be a triangle (checked by size below)."""
    data = path.read_bytes()
    header = data[:data.index(b"end_header\n")].decode()
    vertices = int(re.search(r"element vertex (\d+)", header).group(1))
    faces = int(re.search(r"element face (\d+)", header).group(1))
    body = len(data) - len(header) - len("end_header\n")
    # float x, y, z per vertex; uchar 3 and three int32 per face.
    assert body == 12 * vertices + 13 * faces, f"{path.name}: {body} bytes after the header"
    return faces


class MakeOffice(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.out = pathlib.Path(cls.tmp.name) / "office10k"
        cls.printed = subprocess.run(
            [sys.executable, GENERATOR, "--triangles", "10000", "--out", cls.out],
            check=True, capture_output=True, text=True).stdout

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_counts_what_it_prints_near_the_target(self):
        scene = json.loads((self.out / "office.json").read_text())
        counted = 0
        for shape in scene["shapes"]:
            if shape["type"] == "mesh":
                counted += ply_faces(self.out / shape["file"])
            else:
                self.assertEqual(shape["type"], "quad")
                counted += 2
        printed = int(re.search(r"(\d+) triangles", self.printed).group(1))
        self.assertEqual(counted, printed)
        self.assertLess(abs(counted - 10000), 500)

    def test_same_arguments_same_bytes(self):
        again = pathlib.Path(self.tmp.name) / "again"
        subprocess.run([sys.executable, GENERATOR, "--triangles", "10000", "--out", again],
                       check=True, capture_output=True)
        for path in self.out.iterdir():
            self.assertEqual(path.read_bytes(), (again / path.name).read_bytes(), path.name)

    def test_plan_loads_it_for_radiosity(self):
        # A tiny pilot (8x8 pixels, few photons): this checks loading, not the estimates.
        plan = subprocess.run(
            [BIN_DIR / "lightfarm", "plan", self.out / "office.json", "--method", "path",
             "--resolution", "8", "--pilot-spp", "2", "--photons", "1000", "--threads", "1"],
            capture_output=True, text=True, timeout=60)
        self.assertEqual(plan.returncode, 0, plan.stderr)
        # Two rooms: four emissive quads, one desk lamp, seven Lambertian materials (radiosity's).
        self.assertIn("10 meshes, 0 spheres, 1 point lights", plan.stdout)
        self.assertIn("lights: 8 emissive triangles", plan.stdout)
        self.assertEqual(plan.stdout.count(": lambert,"), 7, plan.stdout)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
