"""Issue 26: OpenPBR's `base_diffuse_roughness` (EON, material/rough_diffuse.rs) against Blender
Cycles' Principled "Diffuse Roughness" (the same model), per object.

    pip install bpy==5.0.1 OpenEXR numpy          # Python 3.11 (e.g. a venv)
    python benches/materials/rough_diffuse_scene.py OUT_DIR LIGHTPATH_BINARY [SPP]

glTF carries no diffuse roughness, so, as subsurface_scene.py does, the geometry, camera and lights
travel as a .glb Blender exports and the materials as an OpenPBR TOML (base_color, base_diffuse_roughness,
specular_weight 0) for Lightpath; Cycles renders the .glb re-imported with each Principled BSDF's
Diffuse Roughness patched in (`cycles_file.py --diffuse-roughness`). Spheres lit from behind and from
the side, where Oren–Nayar differs most from Lambert (a Lambertian copy of each colour is the
control). Prints per-object mean colour errors and the frame. Not a CI dependency.
"""

import math
import os
import subprocess
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.blender import add_camera, add_light, black_world, principled  # noqa: E402

out_dir = os.path.abspath(sys.argv[1])
binary = sys.argv[2]
spp = int(sys.argv[3]) if len(sys.argv) > 3 else 256
W, H = 320, 180
os.makedirs(out_dir, exist_ok=True)
here = os.path.dirname(os.path.abspath(__file__))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
black_world(scene)

# name, base colour, diffuse roughness
OBJECTS = [
    ("clay", (0.8, 0.45, 0.3), 1.0),
    ("clay_smooth", (0.8, 0.45, 0.3), 0.0),
    ("plaster", (0.9, 0.9, 0.85), 0.6),
    ("moss", (0.2, 0.5, 0.1), 0.3),
    ("chalk", (0.95, 0.95, 0.95), 1.0),
]

bpy.ops.mesh.primitive_plane_add(size=20, location=(0, 0, 0))
floor = bpy.context.object
floor.name = "floor"
floor.data.materials.append(principled("floor_mat", (0.5, 0.5, 0.5), roughness=0.9))
r = 0.42
for i, (name, base, _rough) in enumerate(OBJECTS):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=((i - 2) * 1.05, 0.3, r), segments=64,
                                         ring_count=32)
    bpy.ops.object.shade_smooth()
    o = bpy.context.object
    o.name = name
    m = principled(name + "_mat", base, roughness=0.5)
    # No specular layer (OpenPBR's specular_weight 0): the diffuse lobe alone.
    m.node_tree.nodes["Principled BSDF"].inputs["Specular IOR Level"].default_value = 0.0
    o.data.materials.append(m)

add_camera(scene, "shot", 28.0, (0.0, -5.0, 2.2), (math.radians(72.0), 0.0, 0.0))
scene.render.resolution_x, scene.render.resolution_y = W, H
add_light(scene, "sun", "SUN", 2.5, (0, 0, 6), rotation=(math.radians(70), math.radians(-30), 0))
add_light(scene, "key", "POINT", 250.0, (-2.5, -3.0, 3.0), color=(0.9, 0.92, 1.0))
add_light(scene, "back", "POINT", 200.0, (1.0, 3.0, 1.5))
glb = os.path.join(out_dir, "rough_diffuse.glb")
bpy.ops.export_scene.gltf(filepath=glb, export_format="GLB", export_cameras=True, export_lights=True,
                          export_yup=True)


def fmt(v):
    return "[" + ", ".join(f"{x:g}" for x in v) + "]"


toml = os.path.join(out_dir, "rough_diffuse.toml")
with open(toml, "w") as f:
    f.write('[[include]]\nfile = "rough_diffuse.glb"\n\n')
    for name, *_ in OBJECTS:
        f.write(f'[include.objects.{name}]\nmaterial = "{name}"\n\n')
    for name, base, rough in OBJECTS:
        f.write(f'[materials.{name}]\ntype = "openpbr"\nbase_color = {fmt(base)}\n'
                f'base_diffuse_roughness = {rough:g}\nspecular_weight = 0.0\n\n')

py = sys.executable
cy = os.path.join(out_dir, "cycles.exr")
lp = os.path.join(out_dir, "lightpath.exr")
patches = []
for name, _base, rough in OBJECTS:
    patches += ["--diffuse-roughness", f"{name}_mat={rough}"]
subprocess.run([py, os.path.join(here, "cycles_file.py"), glb, "-o", cy, "--spp", str(spp),
                "--resolution", f"{W}x{H}", "--max-bounces", "16", *patches], check=True)
subprocess.run([binary, "render", toml, "-o", lp, "--spp", str(spp), "--resolution", f"{W}x{H}",
                "--max-depth", "17", "--aovs", "none"], check=True)
subprocess.run([py, os.path.join(here, "compare.py"), cy, lp, *[o[0] for o in OBJECTS],
                "--markdown", os.path.join(out_dir, "table.md"), "--limit", "6"], check=True)
