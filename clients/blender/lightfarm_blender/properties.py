"""The add-on's settings and state, kept in each scene (scene.lightfarm) and so in the .blend."""

import bpy
from bpy.props import (CollectionProperty, FloatProperty, PointerProperty, StringProperty)


class LIGHTFARM_Issue(bpy.types.PropertyGroup):
    text: StringProperty()


class LIGHTFARM_Settings(bpy.types.PropertyGroup):
    server: StringProperty(
        name="Farm", default="127.0.0.1:7070",
        description="lightfarm-server's HOST:PORT (empty: LIGHTFARM_SERVER, else 127.0.0.1:7070)")
    token_file: StringProperty(
        name="Token file", subtype="FILE_PATH",
        description="A file whose first line is your submitter token (empty: LIGHTFARM_TOKEN, "
                    "else none, for a farm without tokens)")
    tls_ca: StringProperty(
        name="TLS CA", subtype="FILE_PATH",
        description="PEM of the CA that signed the server's certificate: TLS on (empty: "
                    "LIGHTFARM_TLS_CA, else plain text)")
    export_dir: StringProperty(
        name="Keep export in", subtype="DIR_PATH",
        description="Folder to keep the exported .glb in (empty: a temporary folder, removed "
                    "once uploaded)")
    job_id: StringProperty(name="Job", description="The last job submitted from this scene")
    output_pattern: StringProperty(
        name="Frames to", description="Where Fetch writes the frames: the output path as it "
                                      "was when the job was submitted")
    status: StringProperty(name="Status")
    progress: FloatProperty(name="Progress", min=0, max=1, subtype="FACTOR")
    issues: CollectionProperty(type=LIGHTFARM_Issue)


_CLASSES = (LIGHTFARM_Issue, LIGHTFARM_Settings)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.lightfarm = PointerProperty(type=LIGHTFARM_Settings)


def unregister():
    del bpy.types.Scene.lightfarm
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
