# Checks with Blender (not in CI) where its world shows one bright texel of a 16x8 lat-long map:
# run `blender -b --factory-startup --python tools/blender_env_texel.py`. Each RESULT line gives
# the direction, in Blender's frame and in glTF's, that environment_light_test's
# BrightTexelLightsWhereBlenderShowsIt derives for a Mapping node Z rotation, and the mean radiance
# Cycles renders there (100) and where the opposite turn would put it (0; at rotation 0 a quarter
# turn off, where lightfarm showed it before issue 28).
import bpy, math
from mathutils import Vector, Matrix
W, H, X, Y = 16, 8, 12, 2
scene = bpy.context.scene
for o in list(bpy.data.objects): bpy.data.objects.remove(o)
img = bpy.data.images.new("sky", W, H, float_buffer=True)
px = [0.0] * (W * H * 4)
for i in range(W * H): px[4 * i + 3] = 1.0
r = H - 1 - Y  # Blender stores rows bottom-up
for c in range(3): px[4 * (r * W + X) + c] = 100.0
img.pixels = px
world = bpy.data.worlds.new("w"); scene.world = world; world.use_nodes = True
nt = world.node_tree; nt.nodes.clear()
env = nt.nodes.new("ShaderNodeTexEnvironment"); env.image = img; env.interpolation = "Closest"
bg = nt.nodes.new("ShaderNodeBackground"); out = nt.nodes.new("ShaderNodeOutputWorld")
tc = nt.nodes.new("ShaderNodeTexCoord"); mp = nt.nodes.new("ShaderNodeMapping")
nt.links.new(tc.outputs["Generated"], mp.inputs["Vector"]); nt.links.new(mp.outputs["Vector"], env.inputs["Vector"])
nt.links.new(env.outputs["Color"], bg.inputs["Color"]); nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
scene.render.engine = "CYCLES"; scene.cycles.samples = 4; scene.cycles.device = "CPU"; scene.cycles.use_denoising = False
scene.render.resolution_x = scene.render.resolution_y = 4
cam_data = bpy.data.cameras.new("c"); cam_data.angle = math.radians(2)
cam = bpy.data.objects.new("c", cam_data); scene.collection.objects.link(cam); scene.camera = cam
u = (X + 0.5) / W; v = 1 - (Y + 0.5) / H
phi = -2 * math.pi * u + math.pi; theta = -math.pi * v + math.pi
look = Vector((math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)))
def mean_at(d):
    cam.matrix_world = d.to_track_quat("-Z", "Y").to_matrix().to_4x4()
    scene.render.filepath = "/tmp/blender_env_texel.exr"; scene.render.image_settings.file_format = "OPEN_EXR"
    bpy.ops.render.render(write_still=True)
    im = bpy.data.images.load("/tmp/blender_env_texel.exr", check_existing=False)
    p = list(im.pixels); bpy.data.images.remove(im)
    return sum(p[0::4]) / (len(p) // 4)
for alpha_deg in (0, 90, 30):
    a = math.radians(alpha_deg); mp.inputs["Rotation"].default_value = (0, 0, a)
    d = Matrix.Rotation(-a, 3, "Z") @ look  # Point mapping reads Rz(a) d
    g = (d.x, d.z, -d.y)  # glTF (x, y, z) = Blender (x, z, -y)
    print("RESULT alpha %d blender %s gltf (%.3f %.3f %.3f): there %.2f, opposite-turn %.2f" % (
        alpha_deg, tuple(round(c, 3) for c in d), *g, mean_at(d),
        mean_at(Matrix.Rotation(a, 3, "Z") @ look) if alpha_deg else mean_at(Matrix.Rotation(math.pi/2, 3, "Z") @ look)))
