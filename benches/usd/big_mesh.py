"""Writes one ~1M-triangle mesh (a 708×708 grid of quads with UVs and normals) as Blender
exports it to USD (.usdc) and to glTF (.glb), for the loading benchmark of issue 28:

    /path/to/python3.11 benches/usd/big_mesh.py OUT_DIR
    time lightpath render OUT_DIR/big.usdc --spp 1 --resolution 8x8
    time lightpath render OUT_DIR/big.glb --spp 1 --resolution 8x8
"""

import os
import sys

import bpy

out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "usd-big")
os.makedirs(out, exist_ok=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_grid_add(x_subdivisions=709, y_subdivisions=709, size=4)
bpy.ops.object.shade_smooth()
bpy.ops.wm.usd_export(filepath=os.path.join(out, "big.usdc"))
bpy.ops.export_scene.gltf(filepath=os.path.join(out, "big.glb"), export_format="GLB")
print("wrote", out)
