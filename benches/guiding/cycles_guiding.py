#!/usr/bin/env python3
"""Summarises cycles_guiding.sh: per spp and renderer the median wall and CPU seconds, the
median MSE against the renderer's own converged image (cycles_* against Cycles', mitsuba
against Mitsuba's, lightpath_* against Lightpath's) and against Mitsuba's, efficiency
1 / (MSE x wall s) from the medians and its ratio to Mitsuba's, the same with CPU seconds
(less sensitive to a shared machine's load), and guided over unguided
(MSE per seed, then medians); then the converged images' means against Mitsuba's.

A converged image's own noise adds its variance to every MSE against it. With a reference's
spp given (cycles=REF.exr@4096), that variance is estimated from the unguided runs at the
lowest spp n (MSE x n / (n + ref spp)) and the guided/unguided MSE ratios are also printed
with it subtracted.

Usage: cycles_guiding.py RESULTS OUT cycles=REF.exr[@SPP] mitsuba=REF.exr[@SPP] lightpath=REF.exr[@SPP]
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
refs = dict(r.split("=", 1) for r in refs)
ref_spp = {k: int(v.rsplit("@", 1)[1]) for k, v in refs.items() if "@" in v}
refs = {k: load(v.rsplit("@", 1)[0] if "@" in v else v) for k, v in refs.items()}
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
    print(f"  {'renderer':>22} {'wall s':>7} {'cpu s':>7} {'MSE own':>10} {'MSE mts':>10} {'eff':>8} "
          f"{'eff/mts':>7} {'cpu eff/mts':>11}  mean/own ref (RGB, mean over seeds)  loads")
    eff, effc = {}, {}
    rows = [(r, v) for (s, r), v in runs.items() if s == spp]
    order = ["cycles_off", "cycles_on", "mitsuba", "lightpath_off", "lightpath_on"]
    rows.sort(key=lambda rv: (order.index(rv[0]) if rv[0] in order else 1.5, rv[0]))
    for r, v in rows:
        eff[r] = 1.0 / (med(x["mse"] for x in v.values()) * med(x["wall"] for x in v.values()))
        effc[r] = 1.0 / (med(x["mse"] for x in v.values()) * med(x["cpu"] for x in v.values()))
    for r, v in rows:
        xs = list(v.values())
        mean = np.mean([x["mean"] for x in xs], axis=0)
        ratio = eff[r] / eff["mitsuba"] if "mitsuba" in eff else float("nan")
        ratioc = effc[r] / effc["mitsuba"] if "mitsuba" in effc else float("nan")
        print(f"  {r:>22} {med(x['wall'] for x in xs):7.2f} {med(x['cpu'] for x in xs):7.2f} "
              f"{med(x['mse'] for x in xs):10.3e} {med(x['mse_m'] for x in xs):10.3e} {eff[r]:8.1f} {ratio:7.2f} {ratioc:11.2f}  "
              f"{' '.join(f'{c:.4f}' for c in mean)}  {' '.join(x['load'] for x in xs)}  ({len(xs)} seeds)")
    pairs = [("cycles_off", r) for r, _ in rows if r.startswith("cycles_on")] + [("lightpath_off", "lightpath_on")]
    for name_off, name_on in pairs:
        off, on = runs.get((spp, name_off)), runs.get((spp, name_on))
        if not off or not on:
            continue
        seeds = sorted(set(off) & set(on))
        mse = med(on[s]["mse"] / off[s]["mse"] for s in seeds)
        wall = med(on[s]["wall"] / off[s]["wall"] for s in seeds)
        cpu = med(on[s]["cpu"] / off[s]["cpu"] for s in seeds)
        per_seed = " ".join(f"{on[s]['mse'] / off[s]['mse']:.3f}" for s in seeds)
        fam = name_off.split("_")[0]
        corr = ""
        if fam in ref_spp:
            n = min(sp for sp, r in runs if r == name_off)
            var_ref = med(x["mse"] for x in runs[(n, name_off)].values()) * n / (n + ref_spp[fam])
            corr = (f", {med((on[s]['mse'] - var_ref) / (off[s]['mse'] - var_ref) for s in seeds):.3f} without the "
                    f"converged image's noise (est. {var_ref:.2e})")
        print(f"  {name_on} / {name_off}: MSE {mse:.3f} (per seed {per_seed}), wall {wall:.2f}x, cpu {cpu:.2f}x, "
              f"efficiency {eff[name_on] / eff[name_off]:.2f}x (cpu {effc[name_on] / effc[name_off]:.2f}x){corr}")
m = refs["mitsuba"].reshape(-1, 3).mean(0)
for k, v in refs.items():
    if k != "mitsuba":
        print(f"converged {k} mean / Mitsuba's: {' '.join(f'{c:.5f}' for c in v.reshape(-1, 3).mean(0) / m)}; "
              f"MSE against Mitsuba's {np.mean((v - refs['mitsuba']) ** 2):.3e}")
