#!/usr/bin/env python3
"""Summarises modes.sh: per scene and mode the medians over seeds of wall and CPU seconds
and of the MSE against the reference, 1 / (MSE x seconds) from them, and each image's
mean over the reference's. Usage: modes.py OUT SCENE=REF.exr ..."""
import re
import statistics
import sys

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")


def load(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


out, *refs = sys.argv[1:]
refs = {k: load(v) for k, v in (r.split("=", 1) for r in refs)}
runs = {}
for line in open(f"{out}/results.txt"):
    m = re.match(r"RESULT scene=(\S+) renderer=(\S+) seed=\S+ wall=(\S+) cpu=(\S+) image=(\S+)", line)
    scene, mode, wall, cpu, image = m.groups()
    img, ref = load(f"{out}/{image}"), refs[scene]
    runs.setdefault((scene, mode), []).append(
        (float(wall), float(cpu), float(np.mean((img - ref) ** 2)), img.mean() / ref.mean()))
for (scene, mode), rs in sorted(runs.items()):
    wall, cpu, mse = (statistics.median(r[i] for r in rs) for i in range(3))
    means = " ".join(f"{r[3]:.4f}" for r in rs)
    print(f"{scene:16} {mode:8} wall {wall:6.2f} cpu {cpu:6.2f} MSE {mse:.3e} "
          f"1/(MSE wall) {1 / (mse * wall):8.1f} 1/(MSE cpu) {1 / (mse * cpu):8.1f} mean/ref {means}")
