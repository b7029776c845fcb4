#!/usr/bin/env python3
"""Summarises benches/peer/run.sh: median samples/s per renderer, ratios, and RMSE of each
image against the reference (read with Mitsuba's Bitmap, so no other EXR reader is needed)."""
import re
import statistics
import sys

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")


def load(path):
    return np.array(mi.Bitmap(path))[..., :3].astype(np.float64)


results, ref_path, *images = sys.argv[1:]
speeds = {}
for line in open(results):
    m = re.search(r"variant=(\S+).*?Msamples_per_s(?:_best)?=([0-9.]+)", line)
    if m:
        speeds.setdefault(m.group(1), []).append(float(m.group(2)))
med = {k: statistics.median(v) for k, v in speeds.items()}
for k, v in sorted(med.items()):
    print(f"{k:>26}: {v:6.2f} M samples/s (median of {len(speeds[k])})")
if "lightpath" in med:
    for peer in ("llvm_ad_rgb", "scalar_rgb"):
        if peer in med:
            print(f"lightpath / {peer}: {med['lightpath'] / med[peer]:.2f}x" + (" (target >= 2x)" if peer == "llvm_ad_rgb" else ""))
for base, aovs, what in (
    ("lightpath", "lightpath_40aovs", "cornell-classic, 37 AOVs"),
    ("lightpath_cornell", "lightpath_cornell_44aovs", "cornell, 44 AOVs, 3-group split"),
):
    if base in med and aovs in med:
        print(f"AOV overhead ({what}; AOV time / beauty-only time): {med[base] / med[aovs]:.3f} (target <= 1.15)")
ref = load(ref_path)
for path in images:
    img = load(path)
    rmse = np.sqrt(((img - ref) ** 2).mean())
    mean = img.reshape(-1, 3).mean(0)
    print(f"{path}: RMSE vs reference {rmse:.5f}, mean rgb {np.round(mean, 5).tolist()}")
print(f"reference mean rgb {np.round(ref.reshape(-1, 3).mean(0), 5).tolist()}")
