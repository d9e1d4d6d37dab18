"""lightfarm for Blender: submit the scene to a lightfarm render farm and fetch its frames
(docs/blender.md)."""

bl_info = {
    "name": "lightfarm",
    "author": "lightfarm",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > lightfarm",
    "description": "Render the scene's frames on a lightfarm render farm",
    "category": "Render",
}

import os
import sys

# The zip carries the Python client (lightfarm and its generated lightfarm.v1 stubs) in lib/;
# Blender's Python is Debian's python3, whose grpcio and protobuf it uses.
_LIB = os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib")
if os.path.isdir(_LIB) and _LIB not in sys.path:
    sys.path.insert(0, _LIB)

try:
    import bpy  # noqa: F401 (absent under plain python3, which tests mapping and scene_check)
except ImportError:
    bpy = None

if bpy is not None:
    from . import operators, panel, properties

    _MODULES = (properties, operators, panel)

    def register():
        for module in _MODULES:
            module.register()

    def unregister():
        for module in reversed(_MODULES):
            module.unregister()
