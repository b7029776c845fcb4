#!/usr/bin/env python3
"""Summarises cycles_guiding.sh: per spp and renderer the median wall and CPU seconds, the
median MSE against the renderer's own converged image (cycles_* against Cycles', mitsuba
against Mitsuba's, lightpath_* against Lightpath's) and against Mitsuba's, efficiency
1 / (MSE x wall s) from the medians and its ratio to Mitsuba's, the same with CPU seconds
(less sensitive to a shared machine's load), and guided over unguided
(MSE per seed, then medians); then the converged images' means against Mitsuba's.

Usage: cycles_guiding.py RESULTS OUT cycles=REF.exr mitsuba=REF.exr lightpath=REF.exr
(run with a Python that has numpy and OpenEXR)."""
import os
import re
import statistics
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402


def load(path):
    return rgb(channels(path))


results, out, *refs = sys.argv[1:]
refs = {k: load(v) for k, v in (r.split("=", 1) for r in refs)}
runs = {}
for line in open(results):
    m = re.match(r"RESULT spp=(\d+) renderer=(\S+) seed=(\d+) wall=([0-9.]+) cpu=(\S+) load=(\S+) image=(\S+)", line)
    if not m:
        continue
    spp, renderer, seed, wall, cpu, load_avg, image = m.groups()
    img = load(os.path.join(out, image))
    own = refs[renderer.split("_")[0]]
    runs.setdefault((int(spp), renderer), {})[int(seed)] = dict(
        wall=float(wall), cpu=float(cpu), load=load_avg,
        mse=float(np.mean((img - own) ** 2)), mse_m=float(np.mean((img - refs["mitsuba"]) ** 2)),
        mean=img.reshape(-1, 3).mean(0) / own.reshape(-1, 3).mean(0))

med = statistics.median
for spp in sorted({s for s, _ in runs}):
    print(f"{spp} spp (medians over seeds):")
    print(f"  {'renderer':>14} {'wall s':>7} {'cpu s':>7} {'MSE own':>10} {'MSE mts':>10} {'eff':>8} "
          f"{'eff/mts':>7} {'cpu eff/mts':>11}  mean/own ref (RGB, mean over seeds)  loads")
    eff, effc = {}, {}
    rows = [(r, v) for (s, r), v in runs.items() if s == spp]
    order = ["cycles_off", "cycles_on", "mitsuba", "lightpath_off", "lightpath_on"]
    rows.sort(key=lambda rv: order.index(rv[0]) if rv[0] in order else 99)
    for r, v in rows:
        eff[r] = 1.0 / (med(x["mse"] for x in v.values()) * med(x["wall"] for x in v.values()))
        effc[r] = 1.0 / (med(x["mse"] for x in v.values()) * med(x["cpu"] for x in v.values()))
    for r, v in rows:
        xs = list(v.values())
        mean = np.mean([x["mean"] for x in xs], axis=0)
        ratio = eff[r] / eff["mitsuba"] if "mitsuba" in eff else float("nan")
        ratioc = effc[r] / effc["mitsuba"] if "mitsuba" in effc else float("nan")
        print(f"  {r:>14} {med(x['wall'] for x in xs):7.2f} {med(x['cpu'] for x in xs):7.2f} "
              f"{med(x['mse'] for x in xs):10.3e} {med(x['mse_m'] for x in xs):10.3e} {eff[r]:8.1f} {ratio:7.2f} {ratioc:11.2f}  "
              f"{' '.join(f'{c:.4f}' for c in mean)}  {' '.join(x['load'] for x in xs)}  ({len(xs)} seeds)")
    for name in ("cycles", "lightpath"):
        off, on = runs.get((spp, name + "_off")), runs.get((spp, name + "_on"))
        if not off or not on:
            continue
        seeds = sorted(set(off) & set(on))
        mse = med(on[s]["mse"] / off[s]["mse"] for s in seeds)
        wall = med(on[s]["wall"] / off[s]["wall"] for s in seeds)
        cpu = med(on[s]["cpu"] / off[s]["cpu"] for s in seeds)
        per_seed = " ".join(f"{on[s]['mse'] / off[s]['mse']:.3f}" for s in seeds)
        print(f"  {name} guided/unguided: MSE {mse:.3f} (per seed {per_seed}), wall {wall:.2f}x, cpu {cpu:.2f}x, "
              f"efficiency {eff[name + '_on'] / eff[name + '_off']:.2f}x (cpu {effc[name + '_on'] / effc[name + '_off']:.2f}x)")
m = refs["mitsuba"].reshape(-1, 3).mean(0)
for k, v in refs.items():
    if k != "mitsuba":
        print(f"converged {k} mean / Mitsuba's: {' '.join(f'{c:.5f}' for c in v.reshape(-1, 3).mean(0) / m)}; "
              f"MSE against Mitsuba's {np.mean((v - refs['mitsuba']) ** 2):.3e}")
