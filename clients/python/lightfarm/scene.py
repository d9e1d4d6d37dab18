"""Which files a scene names, found as ``lightfarm submit`` finds them.

The farm loads a scene only from the files uploaded with it, each looked up by the name the scene
uses for it (docs/scene-format.md, docs/farm.md). The C++ client records the names its scene
loader asks for; this module walks the same references without loading the geometry:

* a JSON scene: every ``"file"`` (mesh and glTF shapes, texture objects, sky maps, grid media's
  .vdb files) and every
  ``*_texture`` given as a plain string, by the name as written;
* an OBJ mesh: its ``mtllib`` files, and the textures those MTL files name (``map_Kd``,
  ``map_Ke``, ``norm``, ``map_Bump``, ``map_d``), relative to the file naming them;
* a glTF (``.gltf``, or the JSON chunk of a ``.glb``), the scene itself or one a JSON scene
  includes: its external ``buffers`` and ``images`` (not ``data:`` URIs), relative to the
  glTF's folder as the scene names it, URI-decoded.

Relative names are read beside the scene file, absolute ones as they are. Names derived from
another file's (MTL, textures, glTF buffers) are normalized as the loader does
(``std::filesystem::path::lexically_normal``); names written in the JSON are kept as written.

Anything this walk cannot parse is left to the server, which loads the scene and answers
INVALID_ARGUMENT with the loader's message.
"""

from __future__ import annotations

import json
import os
import posixpath
import struct
import urllib.parse
from typing import Dict, List, Tuple

from .errors import InvalidArgument

MAX_SCENE_PATH_BYTES = 4096


def check_scene_path(path: str) -> None:
    """Raises InvalidArgument unless ``path`` is a usable name (lf::CheckScenePath): 1 to 4096
    bytes, no control characters."""
    n = len(path.encode("utf-8"))
    if n == 0 or n > MAX_SCENE_PATH_BYTES:
        raise InvalidArgument(
            f"scene file name of {n} bytes: expected 1 to {MAX_SCENE_PATH_BYTES}")
    for c in path:
        if ord(c) < 0x20 or ord(c) == 0x7F:
            raise InvalidArgument(
                f"scene file name with control character {ord(c)}: {path!r}")


def _normal(path: str) -> str:
    """std::filesystem::path::lexically_normal for '/' paths (no trailing-slash subtleties)."""
    if not path:
        return path
    n = posixpath.normpath(path)
    if n.startswith("//"):  # POSIX keeps a leading '//', lexically_normal does not
        n = "/" + n.lstrip("/")
    return n


def _beside(file: str, name: str) -> str:
    """A name relative to the folder of the file naming it (mesh_io.cc's Beside)."""
    if posixpath.isabs(name):
        return _normal(name)
    return _normal(posixpath.join(posixpath.dirname(file), name))


def _is_gltf(name: str) -> bool:
    return posixpath.splitext(name)[1].lower() in (".gltf", ".glb")


class _Walker:
    def __init__(self, scene_path: str) -> None:
        self.base = os.path.dirname(scene_path) or "."
        self.scene_name = os.path.basename(scene_path)
        self.files: Dict[str, bytes] = {}

    def read(self, name: str, where: str, required: bool = True):
        """The bytes of `name` (cached), or None when it cannot be read and is not required."""
        if name in self.files:
            return self.files[name]
        path = name if os.path.isabs(name) else os.path.join(self.base, name)
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            if not required:
                return None
            raise InvalidArgument(
                f"{self.scene_name}: {where} \"{name}\": cannot be read ({e.strerror})") from None
        check_scene_path(name)
        self.files[name] = data
        return data

    # --- JSON scenes ---
    def json_scene(self, text: bytes) -> None:
        try:
            root = json.loads(text)
        except ValueError:
            return  # the server's loader says what is wrong, with line and column
        self._walk_json(root, "")

    def _walk_json(self, node, path: str) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                where = f"{path}.{key}" if path else key
                if key == "file" and isinstance(value, str) and value:
                    self.named_file(value, where)
                elif key.endswith("_texture") and isinstance(value, str) and value:
                    self.named_file(value, where)
                else:
                    self._walk_json(value, where)
        elif isinstance(node, list):
            for i, value in enumerate(node):
                self._walk_json(value, f"{path}[{i}]")

    def named_file(self, name: str, where: str) -> None:
        data = self.read(name, where)
        lower = name.lower()
        if _is_gltf(name):
            self.gltf(data, name, posixpath.dirname(name))
        elif lower.endswith(".obj"):
            self.obj(data, name)

    # --- OBJ and MTL ---
    def obj(self, data: bytes, name: str) -> None:
        for line in data.decode("utf-8", "replace").splitlines():
            fields = line.split()
            if len(fields) > 1 and fields[0] == "mtllib":
                for mtl in fields[1:]:
                    mtl_name = _beside(name, mtl)
                    # Read only when the shape uses the OBJ's own materials: the server reports a
                    # missing MTL when it is needed.
                    text = self.read(mtl_name, "mtllib", required=False)
                    if text is not None:
                        self.mtl(text, mtl_name)

    _MTL_TEXTURE_KEYS = {"map_kd", "map_ke", "norm", "map_bump", "bump", "map_d"}

    def mtl(self, data: bytes, name: str) -> None:
        for line in data.decode("utf-8", "replace").splitlines():
            fields = line.split()
            if len(fields) > 1 and fields[0].lower() in self._MTL_TEXTURE_KEYS:
                # Options (-bm 1, -s 1 1 1, ...) come first; the file name is last.
                self.read(_beside(name, fields[-1]), fields[0], required=False)

    # --- glTF ---
    def gltf(self, data: bytes, name: str, base: str) -> None:
        doc = None
        try:
            if data[:4] == b"glTF" and len(data) >= 20:
                length, kind = struct.unpack_from("<II", data, 12)
                if kind == 0x4E4F534A:  # "JSON"
                    doc = json.loads(data[20:20 + length])
            else:
                doc = json.loads(data)
        except (ValueError, struct.error):
            return
        if not isinstance(doc, dict):
            return
        for key in ("buffers", "images"):
            for i, item in enumerate(doc.get(key) or []):
                uri = item.get("uri") if isinstance(item, dict) else None
                if not isinstance(uri, str) or not uri or uri.startswith("data:"):
                    continue
                uri = urllib.parse.unquote(uri)
                ref = uri if posixpath.isabs(uri) else _normal(posixpath.join(base, uri))
                self.read(ref, f"{name}: {key}[{i}].uri")


def scene_files(scene_path: str) -> Tuple[bytes, List[Tuple[str, bytes]]]:
    """The scene file's bytes, and every file it names as (name as the scene uses it, bytes),
    read beside the scene. Raises InvalidArgument for a named file that cannot be read."""
    try:
        with open(scene_path, "rb") as f:
            text = f.read()
    except OSError as e:
        raise InvalidArgument(f"{scene_path}: cannot be read ({e.strerror})") from None
    walker = _Walker(scene_path)
    if _is_gltf(scene_path):
        walker.gltf(text, os.path.basename(scene_path), "")
    else:
        walker.json_scene(text)
    return text, sorted(walker.files.items())
