"""A varied set of many-light scenes (issue 29: "build your own varied set; do not tune to
one"), and the error of each light selection on them at equal samples.

    python3 benches/sampling/many_lights_set.py LIGHTPATH OUT_DIR [SPP] [SEEDS] [VARIANTS]

Writes OUT_DIR/<scene>.toml for six recipes (below), renders a reference of each with the
tree at 64 x SPP samples, then each variant at SPP for SEEDS seeds, and prints per scene
the mean squared error of the beauty against the reference (median over seeds), each
variant's MSE relative to uniform's, its CPU time, and its efficiency (1 / (MSE x CPU
time)) relative to uniform's. VARIANTS is a comma-separated list of `uniform`, `power`,
`tree` (the light selections, one candidate) and `tree:M` / `power:M` (M candidates
resampled, `--light-candidates M`), `tree*N` (N light samples at the first rough vertex,
`--light-samples N`), each optionally with `/independent` (the sampler of
the old build: `uniform/independent`); default `uniform,power,tree`. RECIPES=a,b in the
environment runs only those recipes. 128 x 128, clamps off, lamps hidden from the camera (their sub-pixel
coverage is noise no light selection touches). Needs numpy and OpenEXR.

Recipes (many_lights_recipes.py, shared with many_lights_peers.py; a seeded RNG places
everything, so the set is the same on every run):
  sky_key_lamps  a dim dome, a sun, a point light, 24 small lamps of powers spread 100x
  clusters       three clusters of 16 lamps, the far one 20x brighter
  ceiling_grid   40 one-sided rect lights facing down in a grid, a dim dome
  spots          20 spot lights aimed at random floor points, a dim dome
  two_big_many   two bright rect lights and 60 dim tiny lamps
  corridor       a long corridor lit by 30 lamps along it, viewed down its length
  tuned_many_lights  scenes/many-lights.toml, the scene the tree was tuned on (for contrast)
"""

import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from many_lights_recipes import RECIPES, build, to_toml  # noqa: E402

binary, out = sys.argv[1], sys.argv[2]
spp = int(sys.argv[3]) if len(sys.argv) > 3 else 16
seeds = int(sys.argv[4]) if len(sys.argv) > 4 else 3
variants = (sys.argv[5] if len(sys.argv) > 5 else "uniform,power,tree").split(",")
if "uniform" not in variants:
    variants.insert(0, "uniform")
os.makedirs(out, exist_ok=True)

if os.environ.get("RECIPES"):
    RECIPES = [r for r in RECIPES if r.__name__ in os.environ["RECIPES"].split(",")]


def render(scene, img, variant, n, seed):
    variant, _, sampler = variant.partition("/")
    variant, _, samples = variant.partition("*")
    selection, _, candidates = variant.partition(":")
    args = [binary, "render", scene, "-o", img, "--aovs", "none", "--resolution", "128x128",
            "--spp", str(n), "--seed", str(seed), "--light-selection", selection,
            "--clamp-indirect", "0", "--threads", "1", "--quiet"]
    if candidates:
        args += ["--light-candidates", candidates]
    if samples:
        args += ["--light-samples", samples]
    if sampler:
        args += ["--sampler", sampler]
    t0 = os.times()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    t1 = os.times()
    return t1.children_user - t0.children_user


rows = []
for recipe in RECIPES:
    scene = os.path.join(out, recipe.__name__ + ".toml")
    with open(scene, "w") as f:
        f.write(to_toml(build(recipe)))
    ref = os.path.join(out, recipe.__name__ + "_ref.exr")
    if not os.path.exists(ref):
        render(scene, ref, "tree", 64 * spp, 99)
    r = rgb(channels(ref))
    res = {}
    for sel in variants:
        mses, secs = [], []
        for seed in range(1, seeds + 1):
            tag = sel.replace(":", "_").replace("/", "_").replace("*", "x")
            img = os.path.join(out, f"{recipe.__name__}_{tag}_{seed}.exr")
            secs.append(render(scene, img, sel, spp, seed))
            mses.append(float(((rgb(channels(img)) - r) ** 2).mean()))
        res[sel] = (float(np.median(mses)), float(np.median(secs)))
    rows.append((recipe.__name__, res))
    u, ut = res["uniform"]
    print(f"{recipe.__name__:14s} " + "  ".join(
        f"{s}: MSE {m:.3e} ({u / m:5.2f}x) {t:5.2f} s (eff {u * ut / (m * t):5.2f}x)"
        for s, (m, t) in res.items()), flush=True)
