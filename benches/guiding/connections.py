"""Bidirectional path tracing (`--light-connections on|off`, integrator/connect.rs): the
efficiency of a render with it over one without, on the scenes docs/performance.md,
"Bidirectional path tracing", reports (and "Light-vertex connections" before it).

    python3 benches/guiding/connections.py LIGHTPATH_BINARY OUT_DIR [--seeds 3] [--scenes a,b]

For each scene, each seed and each setting (alternating), one render at the scene's own
spp on 2 threads; its CPU seconds (the whole process) and its MSE against a reference:
Mitsuba's for the indirect box and cornell-classic (benches/guiding/out and
benches/peer/ref, made by benches/peer/mitsuba_cornell.py), for the guiding bench rooms a
4096-spp Lightpath render without connections at seed 999 (made in OUT_DIR if missing).
Prints the medians and efficiency = 1 / (MSE × CPU s), on over off. Needs numpy and the
OpenEXR module; not a CI dependency.
"""

import argparse
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402
from benchlib.run import render_cpu as render  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
# (name, scene, reference or None for a Lightpath one, extra flags)
SCENES = [
    ("room", f"{HERE}/room.toml", None, []),
    ("door", f"{HERE}/door.toml", None, []),
    # Held out: never tuned on (a lamp hidden on a cove shelf; glossy and rough metal balls).
    ("cove", f"{HERE}/cove.toml", None, []),
    # Held out: point and spot lights' subpaths (two hidden uplights, a bulb behind a screen).
    ("uplights", f"{HERE}/uplights.toml", None, []),
    ("indirect_box", f"{HERE}/indirect_box.toml", f"{HERE}/out/indirect_box_ref.exr", []),
    # Distant lights' subpaths: a room lit by the sun through a window, and (held out) a
    # hall lit through a roof slot by a one-direction sun.
    ("sunroom", f"{HERE}/sunroom.toml", None, []),
    ("skylight", f"{HERE}/skylight.toml", None, []),
    # Held out: domes' subpaths (the sunroom under an overcast sky).
    ("skyroom", f"{HERE}/skyroom.toml", None, []),
    ("cornell-classic", f"{ROOT}/scenes/cornell-classic.toml",
     f"{ROOT}/benches/peer/ref/cornell_ref.exr", ["--spp", "64"]),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("out_dir")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--scenes", help="comma-separated names (default: all)")
    args = ap.parse_args()
    wanted = set(args.scenes.split(",")) if args.scenes else None
    os.makedirs(args.out_dir, exist_ok=True)
    print("| scene | CPU s off / on | MSE off / on | efficiency, on ÷ off |")
    print("|---|---|---|---:|")
    for name, scene, ref, extra in SCENES:
        if wanted is not None and name not in wanted:
            continue
        if ref is None:
            ref = f"{args.out_dir}/{name}_ref.exr"
            if not os.path.exists(ref):
                render(args.binary, scene, ref, 999, ["--spp", "4096", "--guiding", "off"])
        reference = rgb(channels(ref))
        runs = {"off": [], "on": []}
        for seed in range(1, args.seeds + 1):
            for mode in ("off", "on"):
                out = f"{args.out_dir}/{name}_{mode}_{seed}.exr"
                cpu = render(args.binary, scene, out, seed, extra + ["--light-connections", mode])
                mse = float(((rgb(channels(out)) - reference) ** 2).mean())
                runs[mode].append((cpu, mse))
        med = {m: [statistics.median(x) for x in zip(*r)] for m, r in runs.items()}
        eff = {m: 1.0 / (c * e) for m, (c, e) in med.items()}
        print(f"| {name} | {med['off'][0]:.2f} / {med['on'][0]:.2f} | "
              f"{med['off'][1]:.3g} / {med['on'][1]:.3g} | {eff['on'] / eff['off']:.2f}× |",
              flush=True)


if __name__ == "__main__":
    main()
