"""Cycles' render of the held-out USD stage of issue 28 (benches/usd/blender_shot.py's
td.usda, the TD's layer over Blender's export), as a Blender user who imports the stage
sees it: the reference compare.py measures Lightpath against.

    /path/to/python3.11 benches/usd/cycles_shot.py OUT_DIR/td.usda -o cycles.exr [--spp 64] [--resolution 320x240]

Writes a multilayer EXR with Combined, one Combined_<light> pass per light (light groups,
the world's as Combined_world) and a CryptoObject layer (its manifest in the header).
Blender's importer turns the DomeLight into the world; the script checks that it did.
Denoising, clamping and adaptive sampling are off.
"""

import argparse
import os
import sys
import time

import bpy

ap = argparse.ArgumentParser()
ap.add_argument("stage")
ap.add_argument("-o", "--out", required=True)
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("--max-bounces", type=int, default=16)
ap.add_argument("--resolution", default="320x240", help="the TD's RenderSettings' (the importer does not read them)")
args = ap.parse_args()

bpy.ops.wm.read_factory_settings(use_empty=True)
sc = bpy.context.scene
# The importer writes the DomeLight into the scene's world, and only when there is one.
sc.world = bpy.data.worlds.new("World")
bpy.ops.wm.usd_import(filepath=os.path.abspath(args.stage), create_world_material=True)
cams = [o for o in sc.objects if o.type == "CAMERA"]
if not cams:
    sys.exit("the stage has no camera")
sc.camera = cams[0]
bgs = [n for n in (sc.world.node_tree.nodes if sc.world.node_tree else []) if n.type == "BACKGROUND"]
if not bgs:
    sys.exit("Blender's importer made no world of the DomeLight")
bg = bgs[0]
print(f"world from the DomeLight: colour {tuple(bg.inputs['Color'].default_value)[:3]}, "
      f"strength {bg.inputs['Strength'].default_value}, "
      f"linked {bg.inputs['Color'].is_linked}")

sc.render.engine = "CYCLES"
sc.cycles.device = "CPU"
sc.cycles.samples = args.spp
sc.cycles.seed = 0
sc.cycles.use_denoising = False
sc.cycles.use_adaptive_sampling = False
sc.cycles.sample_clamp_direct = 0
sc.cycles.sample_clamp_indirect = 0
sc.cycles.caustics_reflective = True
sc.cycles.caustics_refractive = True
for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
          "volume_bounces", "transparent_max_bounces"):
    setattr(sc.cycles, k, args.max_bounces)
w, h = args.resolution.lower().split("x")
sc.render.resolution_x, sc.render.resolution_y = int(w), int(h)
sc.render.resolution_percentage = 100
sc.render.film_transparent = False
vl = sc.view_layers[0]
vl.use_pass_cryptomatte_object = True
vl.pass_cryptomatte_depth = 6
for o in sc.objects:
    if o.type == "MESH":
        print(f"object {o.name} (parent {o.parent.name if o.parent else '-'})")
    if o.type == "LIGHT":
        vl.lightgroups.add(name=o.name)
        o.lightgroup = o.name
        print(f"light group: {o.name} ({o.data.type}, energy {o.data.energy:.4g})")
vl.lightgroups.add(name="world")
sc.world.lightgroup = "world"
imf = sc.render.image_settings
imf.media_type = "MULTI_LAYER_IMAGE"
imf.file_format = "OPEN_EXR_MULTILAYER"
imf.color_depth = "32"
sc.render.filepath = os.path.abspath(args.out)
t = time.time()
bpy.ops.render.render(write_still=True)
print(f"wrote {args.out}: {sc.render.resolution_x}x{sc.render.resolution_y}, "
      f"{args.spp} spp in {time.time() - t:.1f} s")
