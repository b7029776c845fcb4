"""The held-out indirect box against Mitsuba 3 (issue 29's target): efficiency =
1 / (MSE x seconds) of Lightpath with `--light-connections off` and `on`, over Mitsuba 3
`llvm_ad_rgb`'s path tracer at the same 64 spp, per seed, as docs/performance.md,
"Bidirectional path tracing", reports.

    python3 benches/guiding/box_vs_mitsuba.py LIGHTPATH_BINARY OUT_DIR [--seeds 3]

For each seed, in turn: Mitsuba (its second repeat's render time, after the kernel is
compiled), then Lightpath off and on (wall time of the whole process: startup, scene and
EXR included), 2 threads each. MSE against Mitsuba's 8192-spp reference in
benches/guiding/out (made by benches/guiding/efficiency.sh). Needs mitsuba 3.9.1,
numpy and the OpenEXR module; not a CI dependency.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = f"{HERE}/indirect_box.toml"
REF = f"{HERE}/out/indirect_box_ref.exr"


def image(path):
    ch = channels(path)
    if "R" in ch:
        return rgb(ch)
    return rgb(ch, [k for k in ch if k.endswith(".R")][0][:-1])


def mitsuba(out, seed):
    """Renders the box with Mitsuba; returns its render seconds."""
    run = subprocess.run(
        [sys.executable, f"{HERE}/../peer/mitsuba_cornell.py", "--variant", "llvm_ad_rgb",
         "--json", f"{HERE}/indirect_box.json", "--spp", "64", "--max-depth", "8",
         "--threads", "2", "--repeat", "2", "--seed", str(seed), "--out", out],
        check=True, capture_output=True, text=True)
    times = re.findall(r"render_s=([\d.]+)", run.stdout + run.stderr)
    return float(times[-1])


def lightpath(binary, out, seed, mode):
    """Renders the box with Lightpath; returns the process's wall seconds."""
    start = time.perf_counter()
    subprocess.run([binary, "render", SCENE, "--quiet", "--aovs", "none", "--threads", "2",
                    "--seed", str(seed), "--light-connections", mode, "-o", out],
                   check=True, capture_output=True)
    return time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("out_dir")
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    ref = image(REF)
    ratios = {"off": [], "on": []}
    print("| seed | Mitsuba s, MSE | Lightpath off | Lightpath on |")
    print("|---|---|---|---|")
    for seed in range(1, args.seeds + 1):
        mi_out = f"{args.out_dir}/mitsuba_{seed}"
        mi_s = mitsuba(mi_out, seed)
        mi_mse = float(((image(mi_out + ".exr") - ref) ** 2).mean())
        cells = [f"{mi_s:.2f} s, {mi_mse:.3g}"]
        for mode in ("off", "on"):
            out = f"{args.out_dir}/lightpath_{mode}_{seed}.exr"
            s = lightpath(args.binary, out, seed, mode)
            img = image(out)
            mse = float(((img - ref) ** 2).mean())
            ratio = (mi_mse * mi_s) / (mse * s)
            ratios[mode].append(ratio)
            cells.append(f"{s:.2f} s, {mse:.3g}, mean {img.mean() / ref.mean():.4f}: "
                         f"**{ratio:.2f}×**")
        print(f"| {seed} | " + " | ".join(cells) + " |", flush=True)
    for mode, r in ratios.items():
        print(f"median efficiency over Mitsuba, {mode}: {statistics.median(r):.2f}×")


if __name__ == "__main__":
    main()
