"""Per-object mean colour of a Cycles render (cycles_file.py: multilayer EXR with an Object Index
pass) against a Lightpath render of the same .glb and camera.

    python compare.py CYCLES.exr LIGHTPATH.exr NAME... [--markdown OUT.md] [--limit PERCENT]

Objects are numbered as cycles_file.py numbers them (meshes by name, the floor included); each
mask is the object's Object Index pixels eroded by one pixel (the two pixel filters differ at
silhouettes). Errors are (Lightpath / Cycles - 1) per channel, in %."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, erode  # noqa: E402


def find(ch, *cands):
    for c in cands:
        if c in ch:
            return ch[c]
    raise KeyError(f"none of {cands} in {sorted(ch)[:40]}")


args = sys.argv[1:]
md = None
if "--markdown" in args:
    i = args.index("--markdown")
    md = args[i + 1]
    del args[i:i + 2]
limit = 6.0
if "--limit" in args:
    i = args.index("--limit")
    limit = float(args[i + 1])
    del args[i:i + 2]
cy_path, lp_path, names = args[0], args[1], args[2:]
cy, lp = channels(cy_path), channels(lp_path)
c_img = np.stack([find(cy, f"ViewLayer.Combined.{c}") for c in "RGB"], -1)
l_img = np.stack([find(lp, c, f"beauty.{c}") for c in "RGB"], -1)
index = np.rint(find(cy, "ViewLayer.Object Index.X", "ViewLayer.IndexOB.X")).astype(int)
order = sorted(names + ["floor"])


rows = []
for name in names + ["floor"]:
    m = erode(index == order.index(name) + 1)
    if m.sum() == 0:
        rows.append((name, 0, None, None, None))
        continue
    c, l = c_img[m].mean(0), l_img[m].mean(0)
    rows.append((name, int(m.sum()), c, l, 100 * (l / np.maximum(c, 1e-12) - 1)))
c, l = c_img.reshape(-1, 3).mean(0), l_img.reshape(-1, 3).mean(0)
rows.append(("FRAME", c_img.shape[0] * c_img.shape[1], c, l, 100 * (l / c - 1)))

fmt = lambda v: " ".join(f"{x:.4f}" for x in v)
lines = [f"| object | pixels | Cycles RGB | Lightpath RGB | error R % | error G % | error B % | >{limit:g} % |",
         "|---|---|---|---|---|---|---|---|"]
for name, n, c, l, e in rows:
    if c is None:
        lines.append(f"| {name} | 0 | – | – | – | – | – | not visible |")
        continue
    lim = 3 if name == "FRAME" else limit
    bad = "**yes**" if np.abs(e).max() > lim else "no"
    lines.append(f"| {name} | {n} | {fmt(c)} | {fmt(l)} | {e[0]:+.1f} | {e[1]:+.1f} | {e[2]:+.1f} | {bad} |")
print("\n".join(lines))
if md:
    with open(md, "w") as f:
        f.write("\n".join(lines) + "\n")
