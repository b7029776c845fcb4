"""White furnace of Blender Principled metals in Cycles and in Lightpath, side by side: a
white sphere of roughness R and anisotropy A in a white world (radiance 1), mean over the
sphere. A lossless material stays at 1; below 1 is energy the renderer's microfacet model
loses. Explains the anisotropic ball of principled_scene.py (RESULTS.md).

    python benches/materials/cycles_furnace.py OUT_DIR LIGHTPATH_BINARY     # bpy 5.0.1, Python 3.11

Cycles renders the Blender scene; Lightpath renders the same scene exported as .glb (no
light in it, so Lightpath adds its white dome of radiance 1).
"""

import os
import subprocess
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

out, binary = os.path.abspath(sys.argv[1]), sys.argv[2]
os.makedirs(out, exist_ok=True)
N, SPP = 64, 256
rows = []
for name, rough, aniso in [("iso_r0.55", 0.55, 0.0), ("aniso_r0.55_a0.8", 0.55, 0.8),
                           ("aniso_r0.4_a0.8", 0.4, 0.8)]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = SPP
    sc.cycles.use_denoising = False
    for k in ("max_bounces", "glossy_bounces", "diffuse_bounces", "min_light_bounces"):
        setattr(sc.cycles, k, 64)
    sc.cycles.blur_glossy = 0
    sc.render.resolution_x = sc.render.resolution_y = N
    world = bpy.data.worlds.new("white")
    sc.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1, 1, 1, 1)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1, segments=64, ring_count=32)
    ball = bpy.context.object
    bpy.ops.object.shade_smooth()
    m = bpy.data.materials.new("white_metal")
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (1, 1, 1, 1)
    b.inputs["Metallic"].default_value = 1.0
    b.inputs["Roughness"].default_value = rough
    b.inputs["Anisotropic"].default_value = aniso
    ball.data.materials.append(m)
    cam_data = bpy.data.cameras.new("cam")
    cam_data.lens = 50
    cam = bpy.data.objects.new("cam", cam_data)
    sc.collection.objects.link(cam)
    cam.location, cam.rotation_euler = (0, -6, 0), (np.pi / 2, 0, 0)
    sc.camera = cam
    sc.render.image_settings.file_format = "OPEN_EXR"
    cy = os.path.join(out, name + "_cycles.exr")
    sc.render.filepath = cy
    bpy.ops.render.render(write_still=True)
    glb = os.path.join(out, name + ".glb")
    bpy.ops.export_scene.gltf(filepath=glb, export_format="GLB", export_cameras=True)
    lp = os.path.join(out, name + "_lightpath.exr")
    subprocess.run([binary, "render", glb, "-o", lp, "--spp", str(SPP), "--resolution",
                    f"{N}x{N}", "--max-depth", "64", "--aovs", "none"], check=True,
                   capture_output=True)
    # The sphere's disc (50 mm lens on the 36 mm sensor at distance 6), one and a half
    # pixels in from its silhouette.
    r = N * 50 / 36 / 6
    yy, xx = np.mgrid[0:N, 0:N] + 0.5
    mask = (xx - N / 2) ** 2 + (yy - N / 2) ** 2 < (r - 1.5) ** 2
    rows.append((name, rgb(channels(cy))[mask].mean(), rgb(channels(lp))[mask].mean(),
                 int(mask.sum())))
print("| sphere | pixels | Cycles | Lightpath |")
print("|---|---|---|---|")
for name, c, lpv, n in rows:
    print(f"| {name} | {n} | {c:.4f} | {lpv:.4f} |")
