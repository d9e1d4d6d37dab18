"""The lightfarm panel in the Render properties."""

import bpy

from . import mapping


def _summary(scene) -> str:
    """What the farm will render, as the mapping reads the scene now."""
    try:
        r = mapping.read_render(scene, bpy.data.filepath)
        s = mapping.submit_settings(r)
    except ValueError as e:
        return str(e)
    width, height = s["resolution"]
    blur = f", shutter {s['shutter']:g} frames" if s["shutter"] else ""
    return f"{width}x{height}, frames {s['frames']} at {s['fps']:g} fps, {s['spp']} spp{blur}"


class LIGHTFARM_PT_render(bpy.types.Panel):
    bl_label = "lightfarm"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        s = context.scene.lightfarm
        col = layout.column()
        col.prop(s, "server")
        col.prop(s, "token_file")
        col.prop(s, "tls_ca")
        col.prop(s, "export_dir")
        layout.label(text=_summary(context.scene), icon="RENDER_ANIMATION")
        row = layout.row()
        row.operator("lightfarm.check", icon="VIEWZOOM")
        row.operator("lightfarm.submit", icon="EXPORT")
        if s.job_id:
            box = layout.box()
            box.label(text=f"Job {s.job_id}")
            box.prop(s, "progress", slider=True)
            box.label(text=f"Frames to {s.output_pattern}")
            box.operator("lightfarm.fetch", icon="IMPORT")
        if s.status:
            layout.label(text=s.status, icon="INFO")
        if s.issues:
            box = layout.box()
            box.label(text="Does not transfer:", icon="ERROR")
            for issue in s.issues:
                box.label(text=issue.text)


def register():
    bpy.utils.register_class(LIGHTFARM_PT_render)


def unregister():
    bpy.utils.unregister_class(LIGHTFARM_PT_render)
