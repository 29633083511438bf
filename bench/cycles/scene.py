# Blender (3.4) Python: bench/scenes/cloud.pbrt rebuilt for Cycles, rendered
# to a linear EXR. Run by bench/cycles.sh as
#   blender -b --factory-startup -noaudio -t 2 -P bench/cycles/scene.py -- \
#       --vdb volumes/plume.vdb --out OUT.exr --spp N [--seed S] [--step-rate R]
# The mapping from pbrt (left-handed, y up) to Blender (right-handed, z up)
# is (x, y, z) -> (x, z, y): swapping two axes flips the handedness, so the
# image is the same, not mirrored. Every other choice is commented where made.
import argparse
import math
import sys

import bpy
from mathutils import Matrix, Vector

ap = argparse.ArgumentParser(prog="scene.py")
ap.add_argument("--vdb", required=True)
ap.add_argument("--out", required=True)
ap.add_argument("--spp", type=int, default=16)
ap.add_argument("--seed", type=int, default=0)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--step-rate", type=float, default=1.0)  # Cycles' default 1
# pbrt volpath maxdepth N = N scattering vertices, each with its light sample;
# Cycles' volume bounces B = B + 1 vertices (bounces 0: single scattering).
ap.add_argument("--maxdepth", type=int, default=64)
# Cycles samples grid voxel centres half a voxel off OpenVDB's convention
# (which pbrt and haze follow): the object moves by this many voxels.
ap.add_argument("--shift", type=float, default=-0.5)
ap.add_argument("--percent", type=int, default=100)  # quick low-res checks
ap.add_argument("--save-blend", default="")
args = ap.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])


def P(x, y, z):
    """A pbrt point or direction in Blender's axes."""
    return Vector((x, z, y))


# pbrt -> Blender as a matrix (determinant -1).
SWAP = Matrix(((1, 0, 0, 0), (0, 0, 1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

# The camera: LookAt 1.2 1.1 -3.0  -0.05 0.95 -0.05  0 1 0, fov 40 across the
# shorter (vertical) image axis: Blender's vertical sensor fit.
eye, at, up = P(1.2, 1.1, -3.0), P(-0.05, 0.95, -0.05), P(0, 1, 0)
f = (at - eye).normalized()
r = f.cross(up).normalized()
u = r.cross(f)
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "VERTICAL"
cam.sensor_height = 24.0
cam.lens = 12.0 / math.tan(math.radians(20.0))
cam.clip_start, cam.clip_end = 0.01, 1000.0
cam_ob = bpy.data.objects.new("camera", cam)
# Blender cameras look down their -Z with +Y up.
rot = Matrix((r, u, -f)).transposed().to_4x4()
cam_ob.matrix_world = Matrix.Translation(eye) @ rot
scene.collection.objects.link(cam_ob)
scene.camera = cam_ob

# The distant light: "rgb L" [9 8.5 8] from [-2 1.2 -1] towards the origin.
# pbrt's L is the irradiance at normal incidence; so is a Cycles sun's
# strength (W/m^2) times its colour. Angle 0: pbrt's distant light is a delta.
sun = bpy.data.lights.new("sun", "SUN")
sun.energy = 9.0
sun.color = (1.0, 8.5 / 9.0, 8.0 / 9.0)
sun.angle = 0.0
sun_ob = bpy.data.objects.new("sun", sun)
# A sun shines down its -Z: its +Z points at the light.
sun_ob.rotation_euler = P(-2, 1.2, -1).normalized().to_track_quat("Z", "Y").to_euler()
scene.collection.objects.link(sun_ob)

# The "infinite" light rgb L [0.08 0.1 0.14]: a uniform world background
# (radiance = colour x strength), seen by camera rays as pbrt's is.
world = bpy.data.worlds.new("sky")
world.use_nodes = True
bg = world.node_tree.nodes["Background"]
bg.inputs["Color"].default_value = (0.08, 0.1, 0.14, 1.0)
bg.inputs["Strength"].default_value = 1.0
scene.world = world

# The medium: the "density" grid with sigma_a 0.5 and sigma_s 60 per unit
# density, g 0.6. Volume Scatter gives sigma_s = colour x density, Volume
# Absorption sigma_a = (1 - colour) x density; both densities are the grid
# value times the coefficient.
vol = bpy.data.volumes.new("cloud")
vol.filepath = bpy.path.abspath(args.vdb)
vol.grids.load()
grid = vol.grids["density"]
voxel = grid.matrix_object.to_3x3().col[0].length
vol.render.precision = "FULL"  # default HALF rounds the grid to 16 bits
vol.render.space = "OBJECT"
vol.render.step_size = 0.0  # automatic: one voxel, times the step rates
mat = bpy.data.materials.new("cloud")
mat.use_nodes = True
nt = mat.node_tree
for n in list(nt.nodes):
    nt.nodes.remove(n)
out = nt.nodes.new("ShaderNodeOutputMaterial")
attr = nt.nodes.new("ShaderNodeAttribute")
attr.attribute_name = "density"


def scaled(k):
    m = nt.nodes.new("ShaderNodeMath")
    m.operation = "MULTIPLY"
    nt.links.new(attr.outputs["Fac"], m.inputs[0])
    m.inputs[1].default_value = k
    return m.outputs[0]


scat = nt.nodes.new("ShaderNodeVolumeScatter")
scat.inputs["Color"].default_value = (1, 1, 1, 1)
scat.inputs["Anisotropy"].default_value = 0.6
nt.links.new(scaled(60.0), scat.inputs["Density"])
absn = nt.nodes.new("ShaderNodeVolumeAbsorption")
absn.inputs["Color"].default_value = (0, 0, 0, 1)
nt.links.new(scaled(0.5), absn.inputs["Density"])
add = nt.nodes.new("ShaderNodeAddShader")
nt.links.new(scat.outputs[0], add.inputs[0])
nt.links.new(absn.outputs[0], add.inputs[1])
nt.links.new(add.outputs[0], out.inputs["Volume"])
mat.cycles.volume_step_rate = 1.0  # the per-material rate stays 1: the scene's rate decides
vol.materials.append(mat)
ob = bpy.data.objects.new("cloud", vol)
# pbrt places the grid's world coordinates as they are (no transform in the
# scene): here the same axes swap, after the half-voxel shift in grid space.
ob.matrix_world = SWAP @ Matrix.Translation(Vector((1, 1, 1)) * (args.shift * voxel))
scene.collection.objects.link(ob)

# The renderer: Cycles on the CPU, no denoising, no adaptive sampling, no
# clamping, bounces raised to the path depth (factory defaults: volume
# bounces 0, indirect clamp 10, transparent bounces 8).
scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = args.spp
c.seed = args.seed
c.use_adaptive_sampling = False
c.use_denoising = False
c.sample_clamp_direct = 0.0
c.sample_clamp_indirect = 0.0
c.max_bounces = args.maxdepth
c.volume_bounces = args.maxdepth - 1
c.transparent_max_bounces = args.maxdepth
c.volume_step_rate = args.step_rate
c.volume_max_steps = 100000  # never cut a ray short (default 1024)
# pbrt's gaussian: radius 1.5 px, sigma 0.5 px. Cycles' gaussian of width w
# is exp(-2 (6 v / 3w)^2) over |v| < 1.5 w: sigma = w / 4, so w = 2.
c.pixel_filter_type = "GAUSSIAN"
c.filter_width = 2.0
scene.render.threads_mode = "FIXED"
scene.render.threads = args.threads
scene.render.resolution_x, scene.render.resolution_y = 320, 240
scene.render.resolution_percentage = args.percent
scene.render.film_transparent = False
# EXR output is scene-linear whatever the view; Standard anyway, not Filmic.
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0
im = scene.render.image_settings
im.file_format = "OPEN_EXR"
im.color_mode = "RGBA"
im.color_depth = "32"
im.exr_codec = "ZIP"
scene.render.use_file_extension = False
scene.render.filepath = args.out
if args.save_blend:
    bpy.ops.wm.save_as_mainfile(filepath=args.save_blend)
bpy.ops.render.render(write_still=True)
