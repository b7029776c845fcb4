"""Blender Cycles' thin film on a metal, as a curve over the viewing angle: the reference
values of tests_thin_film.rs::metal_film_matches_blender_cycles.

    python benches/materials/thin_film_sphere.py OUT_DIR     # bpy 5.0.1, OpenEXR, numpy

Renders a smooth sphere (Principled BSDF: base colour 0.05, metallic 1, roughness 0, thin
film 400 nm of index 1.33) with an orthographic camera in a white world (strength 1), so
each pixel is the film's Fresnel reflectance at its viewing cosine, read from the normal
pass. Prints the mean colour of the pixels within ±0.004 of each cosine, as Rust.
"""

import math
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels  # noqa: E402

out_dir = os.path.abspath(sys.argv[1])
os.makedirs(out_dir, exist_ok=True)
exr = os.path.join(out_dir, "thin_film_sphere.exr")

bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
bpy.ops.mesh.primitive_uv_sphere_add(radius=1, location=(0, 0, 0), segments=256, ring_count=128)
sphere = bpy.context.object
bpy.ops.object.shade_smooth()
m = bpy.data.materials.new("film")
m.use_nodes = True
b = m.node_tree.nodes["Principled BSDF"]
for k, v in {"Base Color": (0.05, 0.05, 0.05, 1.0), "Metallic": 1.0, "Roughness": 0.0,
             "Thin Film Thickness": 400.0, "Thin Film IOR": 1.33}.items():
    b.inputs[k].default_value = v
sphere.data.materials.append(m)
w = bpy.data.worlds.new("white")
sc.world = w
w.use_nodes = True
w.node_tree.nodes["Background"].inputs["Color"].default_value = (1, 1, 1, 1)
w.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
cd = bpy.data.cameras.new("ortho")
cd.type = "ORTHO"
cd.ortho_scale = 2.2
cam = bpy.data.objects.new("ortho", cd)
sc.collection.objects.link(cam)
cam.location = (0, -10, 0)
cam.rotation_euler = (math.radians(90), 0, 0)  # looking along +y
sc.camera = cam
sc.render.engine = "CYCLES"
sc.cycles.device = "CPU"
sc.cycles.samples = 16
sc.cycles.use_denoising = False
sc.cycles.use_adaptive_sampling = False
sc.cycles.filter_width = 0.01  # one normal per pixel
sc.render.resolution_x = sc.render.resolution_y = 256
sc.view_settings.view_transform = "Standard"
sc.view_layers[0].use_pass_normal = True
imf = sc.render.image_settings
imf.media_type = "MULTI_LAYER_IMAGE"
imf.file_format = "OPEN_EXR_MULTILAYER"
imf.color_depth = "32"
sc.render.filepath = exr
bpy.ops.render.render(write_still=True)

ch = channels(exr)
img = np.stack([ch[f"ViewLayer.Combined.{c}"] for c in "RGB"], -1)
cos = -ch["ViewLayer.Normal.Y"]  # the view direction is -y
print("const CYCLES_SPHERE: [(f32, [f64; 3]); 11] = [")
for target in [1.0, 0.95, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1]:
    sel = np.abs(cos - target) < 0.004
    c = img[sel].mean(0)
    print(f"    ({cos[sel].mean():.4f}, [{c[0]:.5f}, {c[1]:.5f}, {c[2]:.5f}]), // {sel.sum()} pixels")
print("];")
