#!/usr/bin/env python3
"""Solid-angle sampling of rect/quad lights (light/spherical_rect.rs): two Lightpath
builds side by side at equal samples. For each scene, seed and build: CPU seconds (user
+ system of the process, which the shared machine's load inflates less than wall clock),
MSE against a converged Lightpath reference, the image mean over the reference's, and
efficiency = 1 / (MSE x CPU s); medians over seeds. The builds alternate within a seed
so that they share the machine's load.

Usage: rect_lights.py BEFORE AFTER SPP SEEDS name=scene=ref.exr ...
  e.g. rect_lights.py /tmp/lp_before target/release/lightpath 64 3 \\
         box=benches/guiding/indirect_box.toml=out/box_ref.exr cornell=cornell=out/cornell_ref.exr
References: `lightpath render SCENE --aovs none --guiding off --spp 2048 --seed 777`.
"""
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")


def load(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def render(binary, scene, spp, seed, out):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([binary, "render", scene, "--quiet", "--aovs", "none", "--spp", str(spp),
                    "--threads", "2", "--seed", str(seed), "-o", out],
                   check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


before_bin, after_bin, spp, seeds, *scenes = sys.argv[1:]
tmp = tempfile.mkdtemp(prefix="rect_lights_")
for spec in scenes:
    name, scene, ref_path = spec.split("=", 2)
    ref = load(ref_path)
    runs = {"before": [], "after": []}
    for seed in range(1, int(seeds) + 1):
        for build, binary in (("before", before_bin), ("after", after_bin)):
            out = os.path.join(tmp, f"{name}_{build}_{seed}.exr")
            cpu = render(binary, scene, int(spp), seed, out)
            img = load(out)
            mse = float(np.mean((img - ref) ** 2))
            runs[build].append((cpu, mse, img.mean() / ref.mean()))
            print(f"RUN {name} {build} seed={seed} cpu={cpu:.2f} mse={mse:.4e}", flush=True)
    eff = {}
    for build, rs in runs.items():
        cpu = statistics.median(r[0] for r in rs)
        mse = statistics.median(r[1] for r in rs)
        eff[build] = 1.0 / (mse * cpu)
        means = " ".join(f"{r[2]:.4f}" for r in rs)
        print(f"{name:>16} {build:>6}: CPU {cpu:6.2f} s  MSE {mse:.4e}  "
              f"efficiency {eff[build]:9.1f}  mean/ref {means}")
    print(f"{name:>16} after/before: {eff['after'] / eff['before']:.2f}x", flush=True)
