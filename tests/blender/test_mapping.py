"""The add-on's pure modules under plain python3 (ctest blender_mapping): Blender's render
settings to lightfarm's (mapping) and what does not transfer (scene_check), with stand-ins for
bpy's objects. PYTHONPATH: clients/blender and build/python."""

import dataclasses
import types
import unittest

import lightfarm
from lightfarm_blender import farm_jobs, mapping, scene_check

NS = types.SimpleNamespace


def node(kind, **linked):
    return NS(type=kind, inputs={k: NS(is_linked=v) for k, v in linked.items()})


def blender_scene(**changes):
    """A stand-in for factory startup's scene, with Cycles."""
    render = NS(resolution_x=1920, resolution_y=1080, resolution_percentage=100, fps=24,
                fps_base=1.0, use_motion_blur=False, motion_blur_shutter=0.5,
                filepath="//render/", engine="CYCLES", use_border=False, pixel_aspect_x=1.0,
                pixel_aspect_y=1.0)
    world = NS(name="World", use_nodes=True, color=(0.05, 0.05, 0.05),
               node_tree=NS(nodes=[node("OUTPUT_WORLD", Surface=False)]))
    scene = NS(name="Scene", render=render, frame_start=1, frame_end=250, frame_step=1,
               cycles=NS(samples=128, motion_blur_position="CENTER"),
               camera=NS(name="Camera"), world=world, objects=[])
    for key, value in changes.items():
        setattr(render if hasattr(render, key) else scene, key, value)
    return scene


def obj(name, kind, data=None, **extra):
    values = dict(name=name, type=kind, data=data, hide_render=False, particle_systems=[],
                  modifiers=[], animation_data=None, material_slots=[])
    values.update(extra)
    return NS(**values)


class MappingTest(unittest.TestCase):
    def settings(self, **changes):
        return mapping.read_render(blender_scene(**changes), "/shots/sc010.blend")

    def test_factory_scene(self):
        s = mapping.submit_settings(self.settings())
        self.assertEqual(s, dict(resolution=(1920, 1080), frames="1-250", fps=24.0, spp=128,
                                 shutter=0.0, camera="Camera", name="sc010.blend Scene"))
        self.assertEqual(mapping.cli_flags(s), ["--resolution", "1920x1080", "--frames",
                                                "1-250", "--fps", "24.0", "--spp", "128",
                                                "--camera", "Camera"])

    def test_resolution_percentage_rounds_down_as_blender(self):
        r = self.settings(resolution_x=1921, resolution_y=1081, resolution_percentage=33)
        self.assertEqual(mapping.resolution(r), (633, 356))
        self.assertEqual(mapping.resolution(self.settings(resolution_x=2,
                                                          resolution_percentage=1))[0], 1)

    def test_frame_range_and_step(self):
        s = mapping.submit_settings(self.settings(frame_start=-3, frame_end=20, frame_step=4))
        self.assertEqual(s["frames"], "-3-20:4")
        self.assertEqual(list(lightfarm.parse_frames(s["frames"])), [-3, 1, 5, 9, 13, 17])
        with self.assertRaises(ValueError) as caught:
            mapping.submit_settings(self.settings(frame_start=9, frame_end=2))
        self.assertIn("reversed", str(caught.exception))

    def test_fps_is_the_exporters_not_fps_base(self):
        """Blender's glTF exporter writes frame f at f / render.fps seconds (fps_base aside):
        the fps submitted must be that for frame f to be Blender's frame f."""
        s = mapping.submit_settings(self.settings(fps=30, fps_base=1.001))
        self.assertEqual(s["fps"], 30.0)

    def test_motion_blur(self):
        self.assertEqual(mapping.submit_settings(self.settings(use_motion_blur=True,
                                                               motion_blur_shutter=0.3))["shutter"],
                         0.3)
        self.assertEqual(mapping.submit_settings(self.settings(motion_blur_shutter=0.3))["shutter"],
                         0.0)
        flags = mapping.cli_flags(mapping.submit_settings(self.settings(
            use_motion_blur=True, motion_blur_shutter=0.3)))
        self.assertEqual(flags[flags.index("--shutter") + 1], "0.3")

    def test_no_camera(self):
        with self.assertRaises(ValueError) as caught:
            mapping.submit_settings(self.settings(camera=None))
        self.assertIn("no active camera", str(caught.exception))

    def test_output_pattern_names_frames_as_blender(self):
        # Each as RenderSettings.frame_path(frame=4) names it with OpenEXR output (Blender 3.4).
        for path, frame4 in (("//render/shot_", "/shots/render/shot_0004.exr"),
                             ("//render/", "/shots/render/0004.exr"),
                             ("//out.exr", "/shots/out.exr0004.exr"),
                             ("/abs/x_##.png", "/abs/x_04.exr"),
                             ("/abs/x_##_y", "/abs/x_04_y.exr"),
                             ("//a/b_####.exr", "/shots/a/b_0004.exr"),
                             ("", "/shots/0004.exr")):
            pattern = mapping.output_pattern(self.settings(filepath=path))
            self.assertEqual(lightfarm.frame_path(pattern, 4), frame4, path)
        self.assertEqual(lightfarm.frame_path(mapping.output_pattern(
            self.settings(filepath="//s_###")), -3), "/shots/s_-003.exr")
        with self.assertRaises(ValueError) as caught:
            mapping.output_pattern(self.settings(filepath="//r/shot_#_v#"))
        self.assertIn("more than one run", str(caught.exception))
        unsaved = dataclasses.replace(self.settings(), blend_path="")
        with self.assertRaises(ValueError) as caught:
            mapping.output_pattern(unsaved)
        self.assertIn("save it first", str(caught.exception))

    def test_blend_relative(self):
        self.assertEqual(mapping.blend_relative("//keys/a.token", "/shots/sc010.blend"),
                         "/shots/keys/a.token")
        self.assertEqual(mapping.blend_relative("/etc/ca.crt", "/shots/sc010.blend"),
                         "/etc/ca.crt")
        self.assertIsNone(mapping.blend_relative("", "/shots/sc010.blend"))


class SceneCheckTest(unittest.TestCase):
    def test_a_plain_scene_transfers(self):
        scene = blender_scene()
        scene.objects = [obj("Cube", "MESH"), obj("Light", "LIGHT", NS(type="SUN")),
                         obj("Camera", "CAMERA", NS(type="PERSP", dof=NS(use_dof=False)))]
        self.assertEqual(scene_check.scene_issues(scene), [])

    def test_what_does_not_transfer(self):
        scene = blender_scene(engine="BLENDER_EEVEE", use_motion_blur=True)
        scene.cycles.motion_blur_position = "START"
        scene.world.node_tree.nodes[0].inputs["Surface"].is_linked = True
        smoke = NS(name="Smoke", use_nodes=True,
                   node_tree=NS(nodes=[node("OUTPUT_MATERIAL", Surface=False, Volume=True)]))
        wave = NS(data_path='modifiers["Bend"].angle')
        scene.objects = [
            obj("Fog", "VOLUME"), obj("Blob", "META"),
            obj("Panel", "LIGHT", NS(type="AREA")),
            obj("Bulb", "LIGHT", NS(type="POINT", shadow_soft_size=0.25)),
            obj("Lens", "CAMERA", NS(type="PERSP", dof=NS(use_dof=True))),
            obj("Grass", "MESH", particle_systems=[NS(name="Fur", settings=NS(type="HAIR"))],
                modifiers=[NS(name="Cloth", type="CLOTH"), NS(name="Sub", type="SUBSURF")],
                animation_data=NS(action=NS(fcurves=[wave, NS(data_path="location")])),
                material_slots=[NS(material=smoke), NS(material=None)]),
            obj("Hidden", "META", hide_render=True),
        ]
        issues = scene_check.scene_issues(scene)
        for who, what in (("render engine", "BLENDER_EEVEE"), ("motion blur position", "START"),
                          ("world World", "lighting"), ("Fog", "volume object"),
                          ("Blob", "metaball"), ("Panel", "area light"),
                          ("Bulb", "radius 0.25"), ("Lens", "depth of field"),
                          ("Grass", "hair Fur"), ("Grass", "modifier Cloth (CLOTH)"),
                          ('Grass', 'animated modifiers["Bend"]'),
                          ("Grass", "material Smoke")):
            self.assertTrue(any(i.startswith(who) and what in i for i in issues),
                            f"{who}: {what} in {issues}")
        self.assertFalse(any("Hidden" in i or "Sub" in i for i in issues), issues)
        self.assertEqual(len(issues), 12, issues)


class FarmJobsTest(unittest.TestCase):
    def test_a_failure_reaches_the_panel_and_removes_the_export(self):
        """A background task's error is its status (the panel's line), and a temporary export
        goes even when the submission fails."""
        import os
        import tempfile
        folder = tempfile.mkdtemp()
        conn = farm_jobs.Connection("127.0.0.1:1", "/nonexistent/alice.token", None)
        task = farm_jobs.submit(conn, os.path.join(folder, "x.glb"), {}, folder)
        self.assertTrue(task.join(30))
        status = task.status
        self.assertTrue(status["done"])
        self.assertIn("submit: INVALID_ARGUMENT: token_file /nonexistent/alice.token",
                      status["error"])
        self.assertFalse(os.path.exists(folder))


if __name__ == "__main__":
    unittest.main()
