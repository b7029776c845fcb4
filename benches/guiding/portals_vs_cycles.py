"""Dome portals against Blender Cycles' portals: the held-out sky-lit interiors
(skyroom_portal.toml, hall_sky_portal.toml) rendered by Lightpath and by Cycles
(benches/peer/cycles_toml.py builds the same scene in Blender: the window an area light
marked as a portal), each against its own converged image, renderers alternating.

    python3 benches/guiding/portals_vs_cycles.py LIGHTPATH_BINARY OUT_DIR [--seeds 3]
        [--python /work/venv311/bin/python]

Wall seconds: Lightpath's whole process; Cycles' render call (scene sync and BVH in,
Blender's start-up out). References: Lightpath 4096 spp without the portal (seed 999),
Cycles 2048 spp with it (seed 999), made in OUT_DIR if missing. Prints the medians and
the efficiency ratio 1 / (MSE × s), Lightpath over Cycles. Needs numpy, the OpenEXR
module and bpy 5.0.1 (Python 3.11); not a CI dependency.
"""

import argparse
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CYCLES = os.path.join(ROOT, "benches", "peer", "cycles_toml.py")
SCENES = [
    ("skyroom", f"{HERE}/skyroom.toml", f"{HERE}/skyroom_portal.toml"),
    ("hall_sky", f"{HERE}/hall_sky.toml", f"{HERE}/hall_sky_portal.toml"),
]


def lightpath(binary, scene, out, seed, spp):
    t0 = time.time()
    subprocess.run([binary, "render", scene, "-o", out, "--quiet", "--aovs", "none",
                    "--threads", "2", "--seed", str(seed), "--spp", str(spp)],
                   check=True, capture_output=True)
    return time.time() - t0


def cycles(python, scene, out, seed, spp):
    r = subprocess.run([python, CYCLES, scene, out, "--spp", str(spp), "--seed", str(seed)],
                       check=True, capture_output=True, text=True)
    line = [l for l in r.stdout.splitlines() if l.startswith("RENDER_SECONDS")][-1]
    return float(line.split()[1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("out_dir")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--python", default="/work/venv311/bin/python")
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    print("| scene | Lightpath s | Cycles s | MSE Lightpath / Cycles | efficiency ratio |")
    print("|---|---:|---:|---|---:|")
    for name, plain, ported in SCENES:
        lp_ref = f"{args.out_dir}/{name}_lp_ref.exr"
        if not os.path.exists(lp_ref):
            lightpath(args.binary, plain, lp_ref, 999, 4096)
        cy_ref = f"{args.out_dir}/{name}_cy_ref.exr"
        if not os.path.exists(cy_ref):
            cycles(args.python, ported, cy_ref, 999, 2048)
        lref = rgb(channels(lp_ref))
        cref = rgb(channels(cy_ref), "ViewLayer.Combined.")
        lp, cy = [], []
        for seed in range(1, args.seeds + 1):
            out = f"{args.out_dir}/{name}_lp_{seed}.exr"
            s = lightpath(args.binary, ported, out, seed, 64)
            lp.append((s, float(((rgb(channels(out)) - lref) ** 2).mean())))
            out = f"{args.out_dir}/{name}_cy_{seed}.exr"
            s = cycles(args.python, ported, out, seed, 64)
            img = rgb(channels(out), "ViewLayer.Combined.")
            cy.append((s, float(((img - cref) ** 2).mean())))
        (ls, le), (cs, ce) = ([statistics.median(x) for x in zip(*r)] for r in (lp, cy))
        ratio = (cs * ce) / (ls * le)
        print(f"| {name} | {ls:.2f} | {cs:.2f} | {le:.3g} / {ce:.3g} | {ratio:.2f}× |", flush=True)


if __name__ == "__main__":
    main()
