"""Measures Lightpath's render of the held-out USD stage (benches/usd/blender_shot.py's
td.usda) against Cycles' render of the same stage (benches/usd/cycles_shot.py), for the
done-when of issue 28:

    lightpath render td.usda --spp 64 --light-groups --cryptomatte -o lp.exr
    python benches/usd/compare.py cycles.exr lp.exr \\
        --light keygroup=key --light bulb=bulb --light sungroup=sun --light env_light=world \\
        --group balls=Sphere,Sphere_001 --texture Cube

- frame: the beauty's mean, Lightpath / Cycles;
- each light: its share of the beauty (Lightpath's light group over Cycles' Combined_<light>);
- each object: the beauty's mean over the pixels both renderers' CryptoObject mattes give
  wholly to it (coverage ≥ 0.99 in both), Lightpath / Cycles;
- the tagged group: the intersection over union of Lightpath's mask of the group's AOV
  (pixels whose AOV is at least half their beauty) and Cycles' mask of the group's objects
  (their CryptoObject coverage at least one half); also Lightpath's own CryptoObject mask;
- the texture: within the textured object, the share of pixels of each of the checker's two
  colours (orange: red above blue; blue: blue above red) and the pixelwise correlation of
  red / (red + blue) between the two renders.
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, luminance, rgb  # noqa: E402


def crypto_coverage(ch, header, layer, names):
    """Coverage of the objects `names` in the Cryptomatte layer named `layer`."""
    key = next(k.split("/")[1] for k, v in header.items()
               if k.startswith("cryptomatte/") and k.endswith("/name") and v.endswith(layer))
    manifest = json.loads(header[f"cryptomatte/{key}/manifest"])
    ids = {np.uint32(int(manifest[n], 16)) for n in names if n in manifest}
    missing = [n for n in names if n not in manifest]
    if missing:
        raise SystemExit(f"{layer}: no object {missing} in the manifest {sorted(manifest)}")
    prefix = header[f"cryptomatte/{key}/name"]
    cov = None
    rank = 0
    while True:
        lower = f"{prefix}{rank:02d}."
        names_ = [lower + c for c in "rgba"] if lower + "r" in ch else [lower + c for c in "RGBA"]
        if names_[0] not in ch:
            break
        for idc, covc in ((names_[0], names_[1]), (names_[2], names_[3])):
            idv = ch[idc].astype(np.float32).view(np.uint32)
            hit = np.isin(idv, list(ids))
            c = np.where(hit, ch[covc], 0.0)
            cov = c if cov is None else cov + c
        rank += 1
    return cov


ap = argparse.ArgumentParser()
ap.add_argument("cycles")
ap.add_argument("lightpath")
ap.add_argument("--light", action="append", default=[], help="LIGHTPATH_GROUP=CYCLES_LIGHT")
ap.add_argument("--group", action="append", default=[], help="AOV=OBJECT,OBJECT (Cycles names)")
ap.add_argument("--texture", default=None, help="the textured object (Cycles name)")
args = ap.parse_args()

cy_h, lp_h = {}, {}
cy = channels(args.cycles, cy_h)
lp = channels(args.lightpath, lp_h)
cyp = next(k for k in cy if k.endswith("Combined.R"))[: -len("Combined.R")]
b_cy, b_lp = rgb(cy, cyp + "Combined."), rgb(lp, "")
print(f"frame: beauty mean Lightpath / Cycles {luminance(b_lp).mean() / luminance(b_cy).mean():.3f}")

for spec in args.light:
    ours, theirs = spec.split("=")
    l_lp, l_cy = rgb(lp, f"beauty_{ours}."), rgb(cy, f"{cyp}Combined_{theirs}.")
    s_lp, s_cy = luminance(l_lp).mean() / luminance(b_lp).mean(), luminance(l_cy).mean() / luminance(b_cy).mean()
    ratio = l_lp.mean(axis=(0, 1)) / np.maximum(l_cy.mean(axis=(0, 1)), 1e-12)
    print(f"light {ours} / {theirs}: share Lightpath {s_lp:.3f}, Cycles {s_cy:.3f}, "
          f"ratio {s_lp / s_cy:.3f}; mean R G B Lightpath / Cycles "
          f"{ratio[0]:.3f} {ratio[1]:.3f} {ratio[2]:.3f}")

cy_manifest = json.loads(next(v for k, v in cy_h.items() if k.endswith("/manifest")
                              and cy_h[k[: -len("manifest")] + "name"].endswith("CryptoObject")))
for name in sorted(cy_manifest):
    try:
        c_cy = crypto_coverage(cy, cy_h, "CryptoObject", [name])
        c_lp = crypto_coverage(lp, lp_h, "CryptoObject", [name])
    except SystemExit:
        continue
    inside = (c_cy >= 0.99) & (c_lp >= 0.99)
    if inside.sum() < 20:
        continue
    r = luminance(b_lp)[inside].mean() / luminance(b_cy)[inside].mean()
    print(f"object {name}: {inside.sum()} pixels, beauty Lightpath / Cycles {r:.3f}")

for spec in args.group:
    aov, objs = spec.split("=")
    objs = objs.split(",")
    m_cy = crypto_coverage(cy, cy_h, "CryptoObject", objs) >= 0.5
    g = luminance(rgb(lp, aov + "."))
    m_aov = g >= 0.5 * np.maximum(luminance(b_lp), 1e-12)
    m_aov &= luminance(b_lp) > 0
    m_lpc = crypto_coverage(lp, lp_h, "CryptoObject", objs) >= 0.5

    def iou(a, b):
        return (a & b).sum() / max((a | b).sum(), 1)

    print(f"group {aov} ({', '.join(objs)}): IoU of Lightpath's AOV mask with Cycles' "
          f"CryptoObject mask {iou(m_aov, m_cy):.3f} ({m_aov.sum()} and {m_cy.sum()} pixels); "
          f"Lightpath's CryptoObject mask with Cycles' {iou(m_lpc, m_cy):.3f}")

if args.texture:
    c_cy = crypto_coverage(cy, cy_h, "CryptoObject", [args.texture])
    c_lp = crypto_coverage(lp, lp_h, "CryptoObject", [args.texture])
    inside = (c_cy >= 0.99) & (c_lp >= 0.99)
    for who, b in (("Lightpath", b_lp), ("Cycles", b_cy)):
        px = b[inside]
        orange = (px[:, 0] > 1.5 * px[:, 2]).mean()
        blue = (px[:, 2] > 1.5 * px[:, 0]).mean()
        print(f"texture {args.texture} in {who}: {inside.sum()} pixels, orange {orange:.2f}, "
              f"blue {blue:.2f}")
    f_lp = b_lp[inside][:, 0] / np.maximum(b_lp[inside][:, 0] + b_lp[inside][:, 2], 1e-12)
    f_cy = b_cy[inside][:, 0] / np.maximum(b_cy[inside][:, 0] + b_cy[inside][:, 2], 1e-12)
    print(f"texture {args.texture}: correlation of red / (red + blue), Lightpath with Cycles "
          f"{np.corrcoef(f_lp, f_cy)[0, 1]:.3f}")
