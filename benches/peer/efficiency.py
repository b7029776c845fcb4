#!/usr/bin/env python3
"""Summarises benches/peer/efficiency.sh: per scene and renderer the median seconds, the
median MSE against the reference and efficiency = 1 / (MSE x seconds) (from the medians),
then each renderer's efficiency relative to Lightpath's. Images are read with Mitsuba's
Bitmap (RGB of the first layer)."""
import re
import statistics
import sys

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")


def load(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


results, out, *refs = sys.argv[1:]
refs = dict(r.split("=", 1) for r in refs)
runs = {}
for line in open(results):
    m = re.match(r"RESULT scene=(\S+) renderer=(\S+) seconds=([0-9.]+) image=(\S+)", line)
    if m:
        scene, renderer, secs, image = m.groups()
        ref = load(refs[scene]) if scene in refs else None
        img = load(f"{out}/{image}")
        mse = float(np.mean((img - ref) ** 2))
        runs.setdefault((scene, renderer), []).append((float(secs), mse, img.mean() / ref.mean()))
for scene in sorted({s for s, _ in runs}):
    print(f"{scene}:")
    eff = {}
    for (s, renderer), rs in sorted(runs.items()):
        if s != scene:
            continue
        secs = statistics.median(r[0] for r in rs)
        mse = statistics.median(r[1] for r in rs)
        eff[renderer] = 1.0 / (mse * secs)
        # The image's mean over the reference's: a bias shows as the same offset in every run.
        means = " ".join(f"{r[2]:.4f}" for r in rs)
        print(f"  {renderer:>22}: {secs:7.2f} s  MSE {mse:.3e}  RMSE {mse ** 0.5:.5f}  "
              f"efficiency {eff[renderer]:10.1f}  mean/ref {means}  ({len(rs)} runs)")
    for ours in ("lightpath", "lightpath_adaptive", "lightpath_guided", "lightpath_auto"):
        if ours in eff:
            for renderer, e in sorted(eff.items()):
                if renderer != ours:
                    print(f"  {ours} / {renderer}: {eff[ours] / e:.2f}x")
