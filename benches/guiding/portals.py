"""Dome portals (docs/scene-format.md, `portals`; light/portal.rs): the efficiency of a
render of a sky-lit interior with its window given as the dome's portal, over the same
scene without (and over light connections without it), on held-out scenes.

    python3 benches/guiding/portals.py LIGHTPATH_BINARY OUT_DIR [--seeds 3]

For each scene, setting and seed: one render at the scene's own spp on 2 threads, its
CPU seconds (the whole process) and its MSE against a 4096-spp render without the portal
or connections at seed 999 (an independent reference: made in OUT_DIR if missing).
Prints medians, the image mean's offset from the reference, and efficiency =
1 / (MSE × CPU s) over the plain render's. Needs numpy and the OpenEXR module; not a CI
dependency.
"""

import argparse
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402
from benchlib.run import render_cpu as render  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
# (name, scene without the portal, the same with it)
SCENES = [
    ("skyroom", f"{HERE}/skyroom.toml", f"{HERE}/skyroom_portal.toml"),
    ("hall_sky", f"{HERE}/hall_sky.toml", f"{HERE}/hall_sky_portal.toml"),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("out_dir")
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    print("| scene | setting | CPU s | MSE | mean vs reference | efficiency over plain |")
    print("|---|---|---:|---:|---:|---:|")
    for name, plain, ported in SCENES:
        ref = f"{args.out_dir}/{name}_ref.exr"
        if not os.path.exists(ref):
            render(args.binary, plain, ref, 999, ["--spp", "4096", "--guiding", "off"])
        reference = rgb(channels(ref))
        base = None
        for setting, scene, extra in (("plain", plain, []), ("portal", ported, []),
                                      ("connections, no portal", plain,
                                       ["--light-connections", "on"])):
            runs = []
            for seed in range(1, args.seeds + 1):
                out = f"{args.out_dir}/{name}_{setting.split(',')[0]}_{seed}.exr"
                cpu = render(args.binary, scene, out, seed, extra)
                img = rgb(channels(out))
                runs.append((cpu, float(((img - reference) ** 2).mean()),
                             float(img.mean() / reference.mean() - 1.0)))
            cpu, mse, offset = (statistics.median(x) for x in zip(*runs))
            eff = 1.0 / (cpu * mse)
            base = base or eff
            print(f"| {name} | {setting} | {cpu:.2f} | {mse:.3g} | {offset:+.2%} | "
                  f"{eff / base:.2f}× |", flush=True)


if __name__ == "__main__":
    main()
