#!/usr/bin/env python3
"""glTF absorbing glass against Cycles (issue 27: "the held-out glTF's absorbing glass ball
within 10 % of Cycles per channel").

    /work/venv311/bin/python benches/media/gltf_glass.py [--spp 1024] [--cycles-spp 1024]
        [--res 240x180] [--lightpath target/release/lightpath] [--naive]

Builds out/glass.glb with gltf_glass_scene.py (if missing), renders it with Lightpath and
with Blender Cycles through benches/materials/cycles_file.py --gltf-volume (the importer's
Volume Absorption set so that Cycles absorbs KHR_materials_volume's -ln(c)/d; --naive also
renders the plain import, whose Cycles absorption is (1 - c)/d), and prints per channel
the mean of each ball's region and of a floor region, Lightpath over Cycles. Regions are
Cycles' Object Index pass eroded by 2 pixels (the renderers' pixel filters differ at
edges); the standard error of each ratio comes from 8 × 8-pixel blocks. Needs bpy==5.0.1,
numpy and OpenEXR (Python 3.11). Writes out/glass_compare.png (Lightpath | Cycles)."""
import argparse
import os
import re
import subprocess
import sys
import zlib
import struct

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, erode, rgb  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
OUT = os.path.join(HERE, "out")


def ratio(a, b, mask, block=8):
    """Mean of a over mean of b in the mask, per channel, and its standard error from
    blocks of pixels (a delta-method estimate over the blocks' sums)."""
    h, w = mask.shape
    sa, sb, n = [], [], []
    for y in range(0, h, block):
        for x in range(0, w, block):
            m = mask[y:y + block, x:x + block]
            if m.sum() == 0:
                continue
            sa.append(a[y:y + block, x:x + block][m].sum(axis=0))
            sb.append(b[y:y + block, x:x + block][m].sum(axis=0))
            n.append(m.sum())
    sa, sb = np.array(sa), np.array(sb)
    r = sa.sum(axis=0) / sb.sum(axis=0)
    k = len(sa)
    resid = sa - r * sb
    se = np.sqrt(k / max(k - 1, 1) * (resid ** 2).sum(axis=0)) / sb.sum(axis=0)
    return r, se, a[mask].mean(axis=0), b[mask].mean(axis=0)


def write_png(path, img):
    """An sRGB 8-bit PNG, without PIL."""
    c = np.clip(img, 0, 1)
    c = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    px = (c * 255 + 0.5).astype(np.uint8)
    h, w, _ = px.shape
    raw = b"".join(b"\0" + px[y].tobytes() for y in range(h))

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def cycles(glb, out, spp, res, extra):
    log = subprocess.run([sys.executable, os.path.join(ROOT, "benches", "materials", "cycles_file.py"), glb,
                          "-o", out, "--spp", str(spp), "--resolution", res, *extra],
                         check=True, capture_output=True, text=True).stdout
    for line in log.splitlines():
        if "wrote" in line or "absorbs" in line:
            print("  cycles:", line)
    return {m.group(2): int(m.group(1)) for m in re.finditer(r"object index (\d+): (\S+)", log)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--cycles-spp", type=int, default=1024)
    ap.add_argument("--res", default="240x180")
    ap.add_argument("--lightpath", default=os.path.join(ROOT, "target", "release", "lightpath"))
    ap.add_argument("--naive", action="store_true", help="also compare with the plain Blender import")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    glb = os.path.join(OUT, "glass.glb")
    if not os.path.exists(glb):
        subprocess.run([sys.executable, os.path.join(HERE, "gltf_glass_scene.py"), glb], check=True,
                       capture_output=True)
    lp_exr = os.path.join(OUT, f"glass_lightpath_{args.spp}spp.exr")
    subprocess.run([args.lightpath, "render", glb, "-o", lp_exr, "--spp", str(args.spp), "--resolution", args.res,
                    "--max-depth", "16", "--aovs", "none", "-q"], check=True)
    runs = [("gltf-volume", ["--gltf-volume"])] + ([("naive", [])] if args.naive else [])
    lp = rgb(channels(lp_exr), "")
    for label, extra in runs:
        cy_exr = os.path.join(OUT, f"glass_cycles_{label}_{args.cycles_spp}spp.exr")
        index = cycles(glb, cy_exr, args.cycles_spp, args.res, extra)
        ch = channels(cy_exr)
        cy = rgb(ch, "ViewLayer.Combined.")
        ob = ch["ViewLayer.Object Index.X"]
        print(f"Cycles ({label}), Lightpath {args.spp} spp / Cycles {args.cycles_spp} spp, {args.res}:")
        r, se, a, b = ratio(lp, cy, np.ones(ob.shape, bool))
        print(f"  image   ratio {np.round(r, 4)} ± {np.round(se, 4)}  (Lightpath {np.round(a, 4)}, Cycles {np.round(b, 4)})")
        for name in ("green", "amber", "floor", "wall"):
            mask = erode(ob == index[name], 2)
            r, se, a, b = ratio(lp, cy, mask)
            print(f"  {name:7} ratio {np.round(r, 4)} ± {np.round(se, 4)}  (Lightpath {np.round(a, 4)}, "
                  f"Cycles {np.round(b, 4)}, {int(mask.sum())} px)")
        if label == "gltf-volume":
            write_png(os.path.join(OUT, "glass_compare.png"), np.concatenate([lp, cy], axis=1))


if __name__ == "__main__":
    main()
