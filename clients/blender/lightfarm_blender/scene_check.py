"""What of a scene does not reach lightfarm through Blender's glTF exporter (docs/blender.md,
"What does not transfer"). Pure: reads attributes of bpy objects (or stand-ins), never imports
bpy."""

from __future__ import annotations

from typing import Any, List

# Object types the glTF exporter writes no geometry for.
_NOT_EXPORTED = {
    "VOLUME": "a volume object: glTF has no volumes",
    "META": "a metaball: the glTF exporter writes no metaballs",
    "CURVES": "hair curves: glTF has no curves",
    "POINTCLOUD": "a point cloud: glTF export writes no points",
    "GPENCIL": "grease pencil: the glTF exporter writes no strokes",
}
# Modifiers whose result changes from frame to frame: glTF keeps the mesh of one frame.
_TIME_MODIFIERS = {"CLOTH", "SOFT_BODY", "FLUID", "DYNAMIC_PAINT", "OCEAN", "WAVE", "EXPLODE",
                   "PARTICLE_INSTANCE", "MESH_CACHE", "MESH_SEQUENCE_CACHE", "BUILD"}


def _linked(node: Any, socket: str) -> bool:
    inputs = getattr(node, "inputs", None)
    if inputs is None:
        return False
    found = inputs.get(socket) if hasattr(inputs, "get") else None
    return bool(found is not None and found.is_linked)


def _output_nodes(tree: Any, kind: str) -> List[Any]:
    if tree is None:
        return []
    return [n for n in tree.nodes if n.type == kind]


def _lit_world(world: Any) -> bool:
    if world is None:
        return False
    if not getattr(world, "use_nodes", False):
        return any(c > 0 for c in world.color[:3])
    for out in _output_nodes(world.node_tree, "OUTPUT_WORLD"):
        if _linked(out, "Surface"):
            return True
    return False


def _object_issues(obj: Any) -> List[str]:
    issues = []
    if obj.type in _NOT_EXPORTED:
        issues.append(_NOT_EXPORTED[obj.type])
    if obj.type == "LIGHT":
        light = obj.data
        if light.type == "AREA":
            issues.append("an area light: KHR_lights_punctual has point, spot and sun lights "
                          "only, so the exporter drops it (use an emissive mesh)")
        elif light.type in ("POINT", "SPOT") and getattr(light, "shadow_soft_size", 0) > 0:
            issues.append(f"light radius {light.shadow_soft_size:g} m: a punctual light is a "
                          "point (hard shadows)")
    if obj.type == "CAMERA":
        cam = obj.data
        if cam.type == "PANO":
            issues.append("a panoramic camera: glTF cameras are perspective or orthographic")
        if getattr(cam.dof, "use_dof", False):
            issues.append("depth of field: glTF cameras are pinholes")
    for system in getattr(obj, "particle_systems", []):
        kind = "hair" if system.settings.type == "HAIR" else "particle system"
        issues.append(f"{kind} {system.name}: glTF has no particles or hair")
    for mod in getattr(obj, "modifiers", []):
        if mod.type in _TIME_MODIFIERS:
            issues.append(f"modifier {mod.name} ({mod.type}): exported as it is at the current "
                          "frame; its motion does not transfer")
    anim = getattr(obj, "animation_data", None)
    action = getattr(anim, "action", None) if anim else None
    if action is not None:
        animated = sorted({c.data_path.split("]")[0] + "]" for c in action.fcurves
                           if c.data_path.startswith("modifiers[")})
        for path in animated:
            issues.append(f"animated {path}: modifiers are applied at the current frame only")
    for slot in getattr(obj, "material_slots", []):
        mat = slot.material
        if mat is None or not getattr(mat, "use_nodes", False):
            continue
        if any(_linked(out, "Volume") for out in _output_nodes(mat.node_tree,
                                                                "OUTPUT_MATERIAL")):
            issues.append(f"material {mat.name}: its volume shader does not transfer (glTF has "
                          "surfaces only)")
    return issues


def scene_issues(scene: Any) -> List[str]:
    """Each thing of ``scene`` lightfarm will not render as Blender would, "WHO: what and why",
    objects hidden from rendering left out."""
    issues = []
    if scene.camera is None:
        issues.append("scene: no active camera; lightfarm renders from the scene's camera")
    render = scene.render
    if render.engine != "CYCLES":
        issues.append(f"render engine {render.engine}: lightfarm path-traces as Cycles does; "
                      "samples come from the Cycles settings")
    if getattr(render, "use_border", False):
        issues.append("render region (border): lightfarm renders the whole frame")
    if render.pixel_aspect_x != render.pixel_aspect_y:
        issues.append("non-square pixels: lightfarm's pixels are square")
    cycles = getattr(scene, "cycles", None)
    if render.use_motion_blur and getattr(cycles, "motion_blur_position", "CENTER") != "CENTER":
        issues.append(f"motion blur position {cycles.motion_blur_position}: lightfarm centres "
                      "the shutter on the frame")
    if _lit_world(scene.world):
        issues.append(f"world {scene.world.name}: its lighting does not transfer (glTF has no "
                      "environment; lightfarm's background is black)")
    for obj in scene.objects:
        if obj.hide_render:
            continue
        issues.extend(f"{obj.name}: {text}" for text in _object_issues(obj))
    return issues
