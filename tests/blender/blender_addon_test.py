"""The Blender add-on end to end (ctest blender_addon; exit 77, skipped, without blender):
a lightfarm-server with tokens and one worker on a free port, then Blender headless running
addon_script.py (install the zip, build and save a scene, submit, wait, fetch), then
`lightfarm render` of the .glb the add-on exported with the flags it mapped: each fetched frame
must have the local render's pixels bit for bit (every channel) and its header.

Environment (set by ctest, tests/blender/CMakeLists.txt): LF_BIN_DIR, LF_BLENDER_ZIP, and
BLENDER (default: blender on the PATH).
"""

import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'support'))
from processes import stop_all  # noqa: E402  (tests/support)

HERE = os.path.dirname(os.path.abspath(__file__))
SKIP = 77


def exr_parts(path):
    """The header attributes (name -> raw value) and the pixel blocks by first line of a
    scan-line OpenEXR file."""
    with open(path, "rb") as f:
        data = f.read()
    at, attrs = 8, {}
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        attrs[data[at:name_end].decode()] = data[type_end + 5:type_end + 5 + size]
        at = type_end + 5 + size
    at += 1
    y0, y1 = struct.unpack_from("<i", attrs["dataWindow"], 4)[0], \
        struct.unpack_from("<i", attrs["dataWindow"], 12)[0]
    lines = {0: 1, 1: 1, 2: 1, 3: 16}[attrs["compression"][0]]
    chunks = (y1 - y0 + lines) // lines
    blocks = {}
    for offset in struct.unpack_from(f"<{chunks}Q", data, at):
        y, size = struct.unpack_from("<ii", data, offset)
        blocks[y] = data[offset + 8:offset + 8 + size]
    return attrs, blocks


def main():
    blender = os.environ.get("BLENDER") or shutil.which("blender")
    if not blender:
        print("blender_addon: no blender on the PATH: skipped")
        return SKIP
    bin_dir, zip_path = os.environ["LF_BIN_DIR"], os.environ["LF_BLENDER_ZIP"]
    work = tempfile.mkdtemp(prefix="lightfarm-blender-")
    procs = []

    def spawn(name, argv, stdout=subprocess.DEVNULL):
        with open(os.path.join(work, name + ".log"), "w") as log:
            p = subprocess.Popen(argv, stdout=stdout, stderr=log, text=True)
        procs.append(p)
        return p

    def tool(name):
        return os.path.join(bin_dir, name)

    try:
        data, blend_dir = os.path.join(work, "server-data"), os.path.join(work, "blend")
        os.makedirs(blend_dir)
        for name, role, where in (("alice", "submitter", blend_dir), ("node", "worker", work)):
            r = subprocess.run([tool("lightfarm-server"), "token", "create", "--data-dir", data,
                                "--name", name, "--role", role], capture_output=True, text=True,
                               check=True)
            with open(os.path.join(where, name + ".token"), "w") as f:
                f.write(r.stdout.strip().splitlines()[-1] + "\n")
        server = spawn("server", [tool("lightfarm-server"), "--listen", "127.0.0.1:0",
                                  "--data-dir", data, "--log-level", "warn"],
                       stdout=subprocess.PIPE)
        line = server.stdout.readline().strip()
        assert line.startswith("listening on "), line
        address = line[len("listening on "):]
        spawn("worker", [tool("lightfarm-worker"), "--server", address, "--token-file",
                         os.path.join(work, "node.token"), "--threads", "2", "--cache-dir",
                         os.path.join(work, "cache"), "--log-level", "warn"])

        # Blender's user folders in the test's: the add-on installs there, not in $HOME.
        env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.join(work, "scripts"),
                   BLENDER_USER_CONFIG=os.path.join(work, "config"))
        started = time.monotonic()
        r = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1",
                            "--python", os.path.join(HERE, "addon_script.py"), "--",
                            "--zip", zip_path, "--server", address, "--dir", blend_dir],
                           capture_output=True, text=True, env=env, timeout=240)
        seconds = time.monotonic() - started
        if r.returncode != 0 or "addon_script: ok" not in r.stdout:
            print(r.stdout[-4000:], r.stderr[-4000:], sep="\n")
            print("server log:", open(os.path.join(work, "server.log")).read()[-2000:])
            return 1
        print(f"blender: submitted, waited and fetched in {seconds:.1f} s")
        with open(os.path.join(blend_dir, "result.json")) as f:
            result = json.load(f)
        print("mapped flags:", " ".join(result["flags"]))
        print("not transferred:", *result["issues"], sep="\n  ")
        expected = ["--resolution", "32x24", "--frames", "2-6:2", "--fps", "24.0", "--spp", "4",
                    "--shutter", "0.5", "--camera", "Camera"]
        assert result["flags"] == expected, result["flags"]

        local = os.path.join(work, "local_####.exr")
        r = subprocess.run([tool("lightfarm"), "render", result["glb"], *result["flags"], "-o",
                            local, "--threads", "2", "--no-progress"], capture_output=True,
                           text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        timings = {"lightfarm.seconds"}
        pixels = []
        for frame, farm in zip((2, 4, 6), result["paths"]):
            ours, theirs = exr_parts(farm), exr_parts(local.replace("####", f"{frame:04d}"))
            assert ours[1] == theirs[1], f"frame {frame}: the farm's pixels differ from local"
            names = {n for n in ours[0] if n not in timings}
            assert names == {n for n in theirs[0] if n not in timings}, (names, theirs[0])
            for name in names:
                assert ours[0][name] == theirs[0][name], f"frame {frame}: header {name}"
            assert struct.unpack("<i", ours[0]["lightfarm.frame"])[0] == frame
            pixels.append(ours[1])
        assert pixels[0] != pixels[1], "the sphere moves between frames 2 and 4"
        print("frames 2, 4, 6: the farm's bits are lightfarm render's")
        return 0
    finally:
        stop_all(procs)
        for p in procs:
            if p.stdout:
                p.stdout.close()
        if os.environ.get("LF_KEEP_TEST_DIR"):
            print("kept", work)
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
