"""Issue 26, "Done when" 2: white furnace of glTF spheres written by Blender's exporter.

    pip install bpy==5.0.1 OpenEXR numpy          # Python 3.11
    python benches/materials/furnace.py OUT_DIR LIGHTPATH_BINARY [SPP]

Each sphere is alone with a camera and no light, so `lightpath render x.glb` adds its white dome
of radiance 1; lossless white materials should then stay white: mean over the sphere within
[0.98, 1.01]. Max depth 64, roulette as default. The mask is the sphere's alpha (> 0.999) eroded
by one pixel. Not a CI dependency."""

import json
import math
import os
import struct
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels  # noqa: E402

out_dir = os.path.abspath(sys.argv[1])
binary = sys.argv[2]
spp = sys.argv[3] if len(sys.argv) > 3 else "256"
os.makedirs(out_dir, exist_ok=True)
WHITE = (1.0, 1.0, 1.0, 1.0)
CASES = [
    ("white_diffuse_spec0", {"Roughness": 0.5, "Specular IOR Level": 0.0}),
    ("metal_r0.5", {"Metallic": 1.0, "Roughness": 0.5}),
    ("metal_r1", {"Metallic": 1.0, "Roughness": 1.0}),
    ("glass_r0.5", {"Transmission Weight": 1.0, "Roughness": 0.5, "IOR": 1.5}),
    ("plastic_r0.3", {"Roughness": 0.3}),
    ("white_default_spec_r0.5", {"Roughness": 0.5}),
    ("sheen_over_diffuse", {"Roughness": 0.5, "Specular IOR Level": 0.0, "Sheen Weight": 1.0,
                            "Sheen Roughness": 0.5, "Sheen Tint": WHITE}),
    ("coat_over_diffuse", {"Roughness": 0.5, "Specular IOR Level": 0.0, "Coat Weight": 1.0,
                           "Coat Roughness": 0.1}),
]


rows = []
for name, inputs in CASES:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = WHITE
    for k, v in inputs.items():
        b.inputs[k].default_value = v
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, location=(0, 0, 0), segments=96, ring_count=48)
    o = bpy.context.object
    o.name = "sphere"
    bpy.ops.object.shade_smooth()
    o.data.materials.append(m)
    cd = bpy.data.cameras.new("cam")
    cd.lens_unit = "FOV"
    cd.angle = math.radians(30.0)
    cam = bpy.data.objects.new("cam", cd)
    scene.collection.objects.link(cam)
    cam.location = (0, -5.0, 0)
    cam.rotation_euler = (math.radians(90.0), 0, 0)
    scene.camera = cam
    scene.render.resolution_x = scene.render.resolution_y = 128
    glb = os.path.join(out_dir, name + ".glb")
    bpy.ops.export_scene.gltf(filepath=glb, export_format="GLB", export_cameras=True, export_lights=True)
    exr = os.path.join(out_dir, name + ".exr")
    subprocess.run([binary, "render", glb, "-o", exr, "--spp", spp, "--resolution", "128x128",
                    "--max-depth", "64", "--aovs", "none"], check=True, capture_output=True)
    ch = channels(exr)
    a = ch["A"] > 0.999
    e = a.copy()
    e[1:] &= a[:-1]; e[:-1] &= a[1:]; e[:, 1:] &= a[:, :-1]; e[:, :-1] &= a[:, 1:]
    img = np.stack([ch[c] for c in "RGB"], -1)[e]
    mean = img.mean(0)
    se = img.mean(1).std() / math.sqrt(e.sum())
    with open(glb, "rb") as f:
        d = f.read()
    n = struct.unpack("<I", d[12:16])[0]
    ext = sorted(json.loads(d[20:20 + n])["materials"][0].get("extensions", {}))
    ok = 0.98 <= mean.min() and mean.max() <= 1.01
    rows.append(f"| {name} | {', '.join(ext) or '–'} | {int(e.sum())} | {mean[0]:.4f} {mean[1]:.4f} {mean[2]:.4f} "
                f"| {se:.4f} | {'yes' if ok else '**no**'} |")
    print(rows[-1], flush=True)

table = ["| sphere | glTF extensions | pixels | mean RGB | spread/√n | in [0.98, 1.01] |",
         "|---|---|---|---|---|---|"] + rows
print("\n".join(table))
with open(os.path.join(out_dir, "furnace.md"), "w") as f:
    f.write("\n".join(table) + "\n")
