"""Renders Blender's glTF export with Lightpath and compares it with Cycles' render of
the same scene (see blender_scene.py): framing (alpha masks), each light group's
strength (Cycles' light-group passes against Lightpath's beauty_<group>), and the
textured crate (correlation of its pixels).

    python benches/gltf/compare.py OUT_DIR LIGHTPATH_BINARY [SPP]

Needs numpy and OpenEXR (pip install OpenEXR numpy); not a CI dependency.
"""

import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, luminance, rgb  # noqa: E402

out_dir = sys.argv[1]
binary = sys.argv[2]
spp = sys.argv[3] if len(sys.argv) > 3 else "256"
GROUPS = ["key", "spot", "sun"]


subprocess.run(
    [binary, "render", f"{out_dir}/scene.glb", "-o", f"{out_dir}/lightpath.exr",
     "--resolution", "320x240", "--spp", spp, "--max-depth", "9", "--aovs", "none",
     "--light-groups", "--aov", "crate=C<..'crate'>.*[<L.>O]",
     "--aov", "props=C<..'props'>.*[<L.>O]"],
    check=True,
)
lp = channels(f"{out_dir}/lightpath.exr")
cy = channels(f"{out_dir}/cycles.exr")

result = {}
# Framing: the two alpha masks.
a_lp = lp["A"] > 0.5
a_cy = cy["ViewLayer.Combined.A"] > 0.5
iou = float((a_lp & a_cy).sum() / max((a_lp | a_cy).sum(), 1))
result["alpha_iou"] = iou
result["alpha_pixels"] = [int(a_lp.sum()), int(a_cy.sum())]

# Light groups: total light of each, and its share of the beauty.
for g in GROUPS:
    s_lp = rgb(lp, f"beauty_{g}.").sum(axis=(0, 1))
    s_cy = rgb(cy, f"ViewLayer.Combined_{g}.").sum(axis=(0, 1))
    result[f"group_{g}_lightpath_over_cycles"] = [float(x) for x in s_lp / np.maximum(s_cy, 1e-9)]
tot_lp = rgb(lp, "").sum()
tot_cy = rgb(cy, "ViewLayer.Combined.").sum()
result["beauty_lightpath_over_cycles"] = float(tot_lp / tot_cy)

# The textured crate: where its LPE group has light in Lightpath, the two renders'
# luminance should correlate (the checker pattern) and agree in scale.
crate = rgb(lp, "crate.").sum(axis=-1) > 0
c_lp = luminance(rgb(lp, ""))[crate]
c_cy = luminance(rgb(cy, "ViewLayer.Combined."))[crate]
result["crate_pixels"] = int(crate.sum())
result["crate_correlation"] = float(np.corrcoef(c_lp, c_cy)[0, 1])
result["crate_mean_ratio"] = float(c_lp.mean() / c_cy.mean())
# The props collection (glass and chrome under one node): its AOV is non-zero.
result["props_light"] = float(rgb(lp, "props.").sum())

print(json.dumps(result, indent=1))
with open(f"{out_dir}/compare.json", "w") as f:
    json.dump(result, f, indent=1)
