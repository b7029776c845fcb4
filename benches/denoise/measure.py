#!/usr/bin/env python3
"""Denoising quality on cornell-classic (issue 13): RMSE of every standard AOV before and
after `lightpath denoise`, against Lightpath's own high-spp render and (beauty) against
Mitsuba's stored 65536-spp reference, plus the bias floor (Lightpath's own reference
against Mitsuba's) and the error split into light-edge, light and other pixels.

    benches/denoise/measure.py LIGHTPATH [--spp 16] [--ref-spp 4096] [--dir DIR]

LIGHTPATH is a binary built with `--features denoise`. Needs numpy and OpenEXR."""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
MITSUBA = os.path.join(HERE, "..", "peer", "ref", "cornell_ref.exr")


def aov_rgb(img, aov):
    """AOV `aov`'s RGB ("beauty": the beauty), or None if the file has no such AOV."""
    try:
        return rgb(img, "" if aov == "beauty" else aov + ".")
    except KeyError:
        return None


def rmse(a, b, mask=None):
    d = (a - b) ** 2
    if mask is not None:
        d = d[mask]
    return float(np.sqrt(d.mean())) if d.size else 0.0


def run(cmd):
    t = time.time()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.time() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("lightpath")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--dir", default="/tmp/lightpath-denoise-bench")
    ap.add_argument("--quality", default="high")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--extra", default="", help="extra render flags for the noisy render")
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    noisy = os.path.join(a.dir, f"noisy{a.spp}.exr")
    den = os.path.join(a.dir, f"denoised{a.spp}.exr")
    own = os.path.join(a.dir, f"own{a.ref_spp}.exr")
    lp = a.lightpath
    run([lp, "render", "cornell-classic", "--spp", str(a.spp), "--seed", str(a.seed), "-o", noisy] + a.extra.split())
    if not os.path.exists(own):
        t = run([lp, "render", "cornell-classic", "--spp", str(a.ref_spp), "--seed", "99", "-o", own])
        print(f"own reference: {a.ref_spp} spp in {t:.0f} s")
    t = run([lp, "denoise", noisy, "-o", den, "--quality", a.quality])
    print(f"denoise: {t:.2f} s wall")
    subprocess.run([lp, "aovs", den], check=True, stdout=subprocess.DEVNULL)
    print("lightpath aovs on the denoised file: ok")
    n, d, o, m = channels(noisy), channels(den), channels(own), channels(MITSUBA)
    mref = aov_rgb(m, "beauty")
    # Pixel classes from the own reference: light (emission seen in every sample), its
    # edge (partly), the rest.
    em = aov_rgb(o, "emission").max(-1)
    full = em.max()
    light = em >= 0.999 * full
    edge = (em > 0) & ~light
    rest = em == 0
    print(f"pixels: light {light.sum()}, light edge {edge.sum()}, other {rest.sum()}")
    floor = rmse(aov_rgb(o, "beauty"), mref)
    print(f"\nbias floor: own {a.ref_spp}-spp render vs Mitsuba 65536 spp: RMSE {floor:.5f}")
    for name, cls in (("all", None), ("light edge", edge), ("light", light), ("other", rest)):
        print(f"  {name:>10}: {rmse(aov_rgb(o, 'beauty'), mref, cls):.5f}")
    print(f"\nbeauty, {a.spp} spp, RMSE          noisy   denoised  ratio")
    for refname, ref in (("Mitsuba 65536 spp", mref), (f"own {a.ref_spp} spp", aov_rgb(o, "beauty"))):
        for name, cls in (("all", None), ("light edge", edge), ("light", light), ("other", rest)):
            x, y = rmse(aov_rgb(n, "beauty"), ref, cls), rmse(aov_rgb(d, "beauty"), ref, cls)
            print(f"  vs {refname:>17} {name:>10}: {x:.5f}  {y:.5f}  {y / x if x else 0:.3f}")
    # Squared-error shares of the noisy beauty against the own reference.
    tot = ((aov_rgb(n, "beauty") - aov_rgb(o, "beauty")) ** 2).sum()
    for name, cls in (("light edge", edge), ("light", light), ("other", rest)):
        s = ((aov_rgb(n, "beauty") - aov_rgb(o, "beauty")) ** 2)[cls].sum()
        print(f"  share of the noisy squared error, {name}: {s / tot:.2f}")
    print(f"\nper AOV, RMSE against own {a.ref_spp} spp:      noisy   denoised  ratio")
    aovs = sorted({k.rsplit(".", 1)[0] for k in n if "." in k})
    for aov in ["beauty"] + aovs:
        x, y, r = aov_rgb(n, aov), aov_rgb(d, aov), aov_rgb(o, aov)
        if x is None or r is None or y is None:
            continue
        e0, e1 = rmse(x, r), rmse(y, r)
        print(f"  {aov:>18}: {e0:.5f}  {e1:.5f}  {e1 / e0 if e0 else float('nan'):.3f}")


if __name__ == "__main__":
    main()
