#!/usr/bin/env python3
"""Counts fireflies in EXR renders (issue 11): a pixel is an outlier when its beauty's
luminance (Rec. 709 weights) exceeds FACTOR (3) times the median of its 8 neighbours',
and isolated when no neighbour is an outlier too. Border pixels (fewer than 8
neighbours) are not counted. Prints, per file: outliers, isolated outliers, the image's
mean luminance, and with --aov NAME the share of the isolated outliers' excess over their
neighbours' median that the AOV NAME holds (where the fireflies come from).

Usage: fireflies.py [--factor 3] [--aov NAME ...] FILE.exr ...
Reads the beauty as R, G, B (and an AOV as NAME.R/G/B) with the OpenEXR module."""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, luminance, rgb  # noqa: E402


def read_rgb(path, name=None):
    """The beauty's RGB (name None) or AOV `name`'s, as float64 (h, w, 3)."""
    try:
        return rgb(channels(path), "" if name is None else name + ".")
    except KeyError as e:
        sys.exit(f"{path}: {e}")


def neighbour_median(lum):
    h, w = lum.shape
    shifts = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]
    stack = np.stack([lum[1 + dy:h - 1 + dy, 1 + dx:w - 1 + dx] for dy, dx in shifts])
    return np.median(stack, axis=0)


def count(path, factor, aovs):
    lum = luminance(read_rgb(path))
    inner = lum[1:-1, 1:-1]
    med = neighbour_median(lum)
    outlier = np.zeros_like(lum, dtype=bool)
    outlier[1:-1, 1:-1] = inner > factor * med
    h, w = lum.shape
    padded = np.pad(outlier, 1)
    neighbours = sum(
        padded[1 + dy:h + 1 + dy, 1 + dx:w + 1 + dx]
        for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0))
    isolated = outlier & (neighbours == 0)
    line = f"{path}: outliers {int(outlier.sum())} isolated {int(isolated.sum())} mean {lum.mean():.5f}"
    inner_iso = isolated[1:-1, 1:-1]
    excess = (inner - med)[inner_iso].sum()
    for name in aovs:
        a = luminance(read_rgb(path, name))[1:-1, 1:-1]
        a_med = neighbour_median(luminance(read_rgb(path, name)))
        share = (a - a_med)[inner_iso].sum() / excess if excess > 0 else float("nan")
        line += f" {name}:{share:.2f}"
    print(line)
    return int(isolated.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--factor", type=float, default=3.0)
    ap.add_argument("--aov", action="append", default=[])
    ap.add_argument("files", nargs="+")
    args = ap.parse_args()
    for f in args.files:
        count(f, args.factor, args.aov)


if __name__ == "__main__":
    main()
