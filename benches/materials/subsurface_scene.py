"""Issue 26, "Done when" 3: subsurface objects described with OpenPBR's parameter names (a TOML
scene) against Blender Cycles' random-walk render of the same objects, within 8 % per object.

    pip install bpy==5.0.1 OpenEXR numpy          # Python 3.11 (e.g. a venv)
    python benches/materials/subsurface_scene.py OUT_DIR LIGHTPATH_BINARY [SPP]
    KEEP_CYCLES=1 python …        # reuse OUT_DIR/cycles.exr (same objects, another Lightpath)

glTF has no subsurface extension, so the geometry, camera and lights travel as a .glb that
Blender exports (OUT_DIR/subsurface.glb) and the materials do not: Cycles renders the .glb
re-imported with each Principled BSDF patched to random-walk subsurface (`cycles_file.py
--subsurface`), Lightpath renders OUT_DIR/subsurface.toml, which includes the .glb and gives each
object an OpenPBR material written from the same numbers: base_color = subsurface_color = Base
Color, subsurface_radius = Subsurface Scale / (4 pi), subsurface_radius_scale = Subsurface Radius,
subsurface_scatter_anisotropy = Subsurface Anisotropy, specular_roughness = Roughness,
specular_ior = IOR. The 1 / (4 pi): Cycles' "Random Walk" method walks with the mean free path
Radius x Scale / (4 pi) (intern/cycles/kernel/closure/bssrdf.h, bssrdf_setup_radius: "so it gives
similar looking result to older Cubic, Gaussian and Burley models"), OpenPBR's subsurface_radius is
the mean free path itself. Prints per-object mean colour errors (Cycles' Object Index masks) and the
frame. Not a CI dependency.
"""

import math
import os
import subprocess
import sys

import bpy

out_dir = os.path.abspath(sys.argv[1])
binary = sys.argv[2]
spp = int(sys.argv[3]) if len(sys.argv) > 3 else 256
W, H = 320, 180
os.makedirs(out_dir, exist_ok=True)
here = os.path.dirname(os.path.abspath(__file__))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene

# name, base colour, roughness, subsurface radius (RGB), scale, anisotropy, shape
OBJECTS = [
    ("skin", (0.8, 0.5, 0.4), 0.5, (1.0, 0.35, 0.2), 0.1, 0.0, "sphere"),
    ("jade", (0.3, 0.8, 0.45), 0.2, (0.3, 1.0, 0.5), 0.2, 0.0, "sphere"),
    ("marble", (0.9, 0.9, 0.88), 0.3, (1.0, 1.0, 1.0), 0.05, 0.0, "sphere"),
    ("wax", (0.9, 0.6, 0.2), 0.4, (1.0, 0.6, 0.3), 0.3, 0.0, "sphere"),
    ("milk", (0.95, 0.95, 0.93), 0.1, (1.0, 0.9, 0.8), 0.5, 0.0, "sphere"),
    ("soap", (0.6, 0.75, 0.9), 0.3, (0.5, 0.8, 1.0), 0.15, 0.6, "cube"),
]
IOR = 1.5


def principled(name, base, rough):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (*base, 1.0)
    b.inputs["Roughness"].default_value = rough
    b.inputs["IOR"].default_value = IOR
    return m


bpy.ops.mesh.primitive_plane_add(size=20, location=(0, 0, 0))
floor = bpy.context.object
floor.name = "floor"
floor.data.materials.append(principled("floor_mat", (0.5, 0.5, 0.5), 0.9))

r = 0.42
for i, (name, base, rough, _radius, _scale, _aniso, shape) in enumerate(OBJECTS):
    x = (i - 2.5) * 1.05
    if shape == "cube":
        bpy.ops.mesh.primitive_cube_add(size=2 * r * 0.85, location=(x, 0.3, r * 0.85),
                                        rotation=(0, 0, math.radians(30)))
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=(x, 0.3, r), segments=64, ring_count=32)
        bpy.ops.object.shade_smooth()
    o = bpy.context.object
    o.name = name
    o.data.materials.append(principled(name + "_mat", base, rough))

cam_data = bpy.data.cameras.new("shot")
cam_data.sensor_fit = "HORIZONTAL"
cam_data.lens_unit = "FOV"
cam_data.angle = math.radians(45.0)
cam = bpy.data.objects.new("shot", cam_data)
scene.collection.objects.link(cam)
cam.location = (0.0, -5.0, 2.2)
cam.rotation_euler = (math.radians(72.0), 0.0, 0.0)
scene.camera = cam
scene.render.resolution_x, scene.render.resolution_y = W, H


def light(name, kind, energy, location, rotation=(0, 0, 0), color=(1, 1, 1)):
    d = bpy.data.lights.new(name, kind)
    d.energy, d.color = energy, color
    if kind == "POINT":
        d.shadow_soft_size = 0.0
    if kind == "SUN":
        d.angle = 0.0
    o = bpy.data.objects.new(name, d)
    o.location, o.rotation_euler = location, rotation
    scene.collection.objects.link(o)


# A back light makes the light that travels through the objects count.
light("sun", "SUN", 2.5, (0, 0, 6), rotation=(math.radians(40), math.radians(20), 0), color=(1.0, 0.95, 0.9))
light("key", "POINT", 250.0, (-2.5, -3.0, 3.0), color=(0.9, 0.92, 1.0))
light("back", "POINT", 200.0, (1.0, 3.0, 1.5))
glb = os.path.join(out_dir, "subsurface.glb")
bpy.ops.export_scene.gltf(filepath=glb, export_format="GLB", export_cameras=True, export_lights=True,
                          export_yup=True)
print("wrote", glb)


def fmt(v):
    return "[" + ", ".join(f"{x:g}" for x in v) + "]"


toml = os.path.join(out_dir, "subsurface.toml")
with open(toml, "w") as f:
    f.write('[[include]]\nfile = "subsurface.glb"\n\n')
    for name, *_ in OBJECTS:
        f.write(f'[include.objects.{name}]\nmaterial = "{name}"\n\n')
    for name, base, rough, radius, scale, aniso, _shape in OBJECTS:
        f.write(f'[materials.{name}]\ntype = "openpbr"\nbase_color = {fmt(base)}\n'
                f'specular_roughness = {rough:g}\nspecular_ior = {IOR:g}\n'
                f'subsurface_weight = 1.0\nsubsurface_color = {fmt(base)}\n'
                f'subsurface_radius = {scale / (4 * math.pi):g}\nsubsurface_radius_scale = {fmt(radius)}\n'
                f'subsurface_scatter_anisotropy = {aniso:g}\n\n')
print("wrote", toml)

py = sys.executable
cy = os.path.join(out_dir, "cycles.exr")
lp = os.path.join(out_dir, "lightpath.exr")
patches = []
for name, _base, _rough, radius, scale, aniso, _shape in OBJECTS:
    patches += ["--subsurface", f"{name}_mat={','.join(map(str, radius))}:{scale}:{aniso}"]
if not os.environ.get("KEEP_CYCLES") or not os.path.exists(cy):
    subprocess.run([py, os.path.join(here, "cycles_file.py"), glb, "-o", cy, "--spp", str(spp),
                    "--resolution", f"{W}x{H}", "--max-bounces", "16", *patches], check=True)
subprocess.run([binary, "render", toml, "-o", lp, "--spp", str(spp), "--resolution", f"{W}x{H}",
                "--max-depth", "17", "--aovs", "none"], check=True)
subprocess.run([py, os.path.join(here, "compare.py"), cy, lp, *[o[0] for o in OBJECTS],
                "--markdown", os.path.join(out_dir, "table.md"), "--limit", "8"], check=True)
