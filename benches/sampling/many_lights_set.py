"""A varied set of many-light scenes (issue 29: "build your own varied set; do not tune to
one"), and the error of each light selection on them at equal samples.

    python3 benches/sampling/many_lights_set.py LIGHTPATH OUT_DIR [SPP] [SEEDS] [VARIANTS]

Writes OUT_DIR/<scene>.toml for six recipes (below), renders a reference of each with the
tree at 64 x SPP samples, then each variant at SPP for SEEDS seeds, and prints per scene
the mean squared error of the beauty against the reference (median over seeds), each
variant's MSE relative to uniform's, its CPU time, and its efficiency (1 / (MSE x CPU
time)) relative to uniform's. VARIANTS is a comma-separated list of `uniform`, `power`,
`tree` (the light selections, one candidate) and `tree:M` / `power:M` (M candidates
resampled, `--light-candidates M`), each optionally with `/independent` (the sampler of
the old build: `uniform/independent`); default `uniform,power,tree`. RECIPES=a,b in the
environment runs only those recipes. 128 x 128, clamps off, lamps hidden from the camera (their sub-pixel
coverage is noise no light selection touches). Needs numpy and OpenEXR.

Recipes (a seeded RNG places everything, so the set is the same on every run):
  sky_key_lamps  a dim dome, a sun, a point light, 24 small lamps of powers spread 100x
  clusters       three clusters of 16 lamps, the far one 20x brighter
  ceiling_grid   40 one-sided rect lights facing down in a grid, a dim dome
  spots          20 spot lights aimed at random floor points, a dim dome
  two_big_many   two bright rect lights and 60 dim tiny lamps
  corridor       a long corridor lit by 30 lamps along it, viewed down its length
  tuned_many_lights  scenes/many-lights.toml, the scene the tree was tuned on (for contrast)
"""

import os
import random
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

binary, out = sys.argv[1], sys.argv[2]
spp = int(sys.argv[3]) if len(sys.argv) > 3 else 16
seeds = int(sys.argv[4]) if len(sys.argv) > 4 else 3
variants = (sys.argv[5] if len(sys.argv) > 5 else "uniform,power,tree").split(",")
if "uniform" not in variants:
    variants.insert(0, "uniform")
os.makedirs(out, exist_ok=True)


def room(w=10.0, d=8.0, h=4.0, camera=((0, 2.2, 6.5), (0, 0.6, 0))):
    (px, py, pz), (lx, ly, lz) = camera
    s = f"""[camera]
position = [{px}, {py}, {pz}]
look_at = [{lx}, {ly}, {lz}]
fov = 50.0

[render]
max_depth = 6
rr_depth = 4

[materials.floor]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]
[materials.wall]
type = "diffuse"
albedo = [0.6, 0.55, 0.5]
[materials.blue]
type = "diffuse"
albedo = [0.2, 0.3, 0.7]
[materials.metal]
type = "conductor"
f0 = [0.9, 0.9, 0.9]
roughness = 0.3

[[objects]]
name = "floor"
shape = "quad"
material = "floor"
corners = [[{-w/2}, 0, {d/2}], [{w/2}, 0, {d/2}], [{w/2}, 0, {-d/2}], [{-w/2}, 0, {-d/2}]]
[[objects]]
name = "backWall"
shape = "quad"
material = "wall"
corners = [[{-w/2}, 0, {-d/2}], [{w/2}, 0, {-d/2}], [{w/2}, {h}, {-d/2}], [{-w/2}, {h}, {-d/2}]]
[[objects]]
name = "box"
shape = "cube"
material = "blue"
scale = [0.5, 0.5, 0.5]
rotate = [0, 30, 0]
translate = [-1.2, 0.5, -0.5]
[[objects]]
name = "ball"
shape = "sphere"
material = "metal"
center = [1.2, 0.6, 0.2]
radius = 0.6
"""
    return s


def lamp(x, y, z, power, r=0.04):
    rgb = [power * c for c in random.choice([(1, .5, .2), (.3, 1, .3), (.2, .4, 1), (1, .9, .8)])]
    return (f'[[lights]]\ntype = "sphere"\ngroups = ["lamps"]\ncamera_visible = false\n'
            f'center = [{x:.3f}, {y:.3f}, {z:.3f}]\nradius = {r}\n'
            f'radiance = [{rgb[0]:.2f}, {rgb[1]:.2f}, {rgb[2]:.2f}]\n\n')


def dome(v=0.03):
    return f'[[lights]]\ntype = "dome"\nname = "sky"\nradiance = [{v}, {v * 1.3:.3f}, {v * 2:.3f}]\n\n'


def sky_key_lamps():
    s = room() + dome()
    s += '[[lights]]\ntype = "distant"\nname = "sun"\ndirection = [0.4, -1, -0.3]\nirradiance = [2.0, 1.8, 1.5]\n\n'
    s += '[[lights]]\ntype = "point"\nname = "bulb"\nposition = [2.5, 2.5, 1.0]\nintensity = [4, 4, 4]\n\n'
    for _ in range(24):
        s += lamp(random.uniform(-4, 4), random.uniform(0.2, 2.5), random.uniform(-3.5, 3),
                  10 ** random.uniform(0.5, 2.5))
    return s


def clusters():
    s = room() + dome(0.01)
    for cx, cz, power in ((-3, 2, 20), (3, 1, 20), (0, -3.5, 400)):
        for _ in range(16):
            s += lamp(cx + random.gauss(0, 0.4), random.uniform(0.3, 1.5), cz + random.gauss(0, 0.3), power)
    return s


def ceiling_grid():
    s = room() + dome(0.02)
    for i in range(8):
        for j in range(5):
            x, z = -3.5 + i, -3 + 1.4 * j
            p = 10 ** random.uniform(0, 1.3)
            s += (f'[[lights]]\ntype = "rect"\ngroups = ["panels"]\ncamera_visible = false\n'
                  f'radiance = [{p:.2f}, {p:.2f}, {p * 0.9:.2f}]\nrotate = [90, 0, 0]\n'
                  f'translate = [{x}, 3.9, {z}]\nscale = [0.15, 0.15, 1]\n\n')
    return s


def spots():
    s = room() + dome(0.02)
    for _ in range(20):
        x, y, z = random.uniform(-4, 4), random.uniform(2.5, 3.8), random.uniform(-3, 3)
        tx, tz = random.uniform(-4, 4), random.uniform(-3.5, 3.5)
        p = 10 ** random.uniform(0.5, 1.5)
        s += (f'[[lights]]\ntype = "spot"\ngroups = ["spots"]\nposition = [{x:.2f}, {y:.2f}, {z:.2f}]\n'
              f'direction = [{tx - x:.2f}, {-y:.2f}, {tz - z:.2f}]\ncone_angle = {random.uniform(15, 50):.1f}\n'
              f'cone_softness = 5\nintensity = [{p:.2f}, {p:.2f}, {p:.2f}]\n\n')
    return s


def two_big_many():
    s = room()
    for x in (-2.5, 2.5):
        s += (f'[[lights]]\ntype = "rect"\ngroups = ["big"]\nradiance = [12, 11, 10]\nrotate = [90, 0, 0]\n'
              f'translate = [{x}, 3.9, 0]\nscale = [0.5, 0.5, 1]\ncamera_visible = false\n\n')
    for _ in range(60):
        s += lamp(random.uniform(-4.5, 4.5), random.uniform(0.1, 0.6), random.uniform(-3.5, 3.5),
                  10 ** random.uniform(0.3, 1.3), r=0.02)
    return s


def corridor():
    s = room(w=3.0, d=30.0, h=3.0, camera=((0, 1.6, 14.5), (0, 1.2, 0))) + dome(0.005)
    for i in range(30):
        z = 14 - i
        s += lamp(random.choice((-1.3, 1.3)), 2.6, z, 10 ** random.uniform(1, 2))
    return s


def tuned_many_lights():
    """scenes/many-lights.toml, the scene the tree was tuned on (lamps hidden, as above)."""
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "..", "scenes", "many-lights.toml")) as f:
        text = f.read()
    return text.replace('groups = ["lamps"]\n', 'groups = ["lamps"]\ncamera_visible = false\n')


RECIPES = [sky_key_lamps, clusters, ceiling_grid, spots, two_big_many, corridor, tuned_many_lights]
if os.environ.get("RECIPES"):
    RECIPES = [r for r in RECIPES if r.__name__ in os.environ["RECIPES"].split(",")]


def render(scene, img, variant, n, seed):
    variant, _, sampler = variant.partition("/")
    selection, _, candidates = variant.partition(":")
    args = [binary, "render", scene, "-o", img, "--aovs", "none", "--resolution", "128x128",
            "--spp", str(n), "--seed", str(seed), "--light-selection", selection,
            "--clamp-indirect", "0", "--threads", "1", "--quiet"]
    if candidates:
        args += ["--light-candidates", candidates]
    if sampler:
        args += ["--sampler", sampler]
    t0 = os.times()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    t1 = os.times()
    return t1.children_user - t0.children_user


rows = []
for recipe in RECIPES:
    random.seed(recipe.__name__)
    scene = os.path.join(out, recipe.__name__ + ".toml")
    with open(scene, "w") as f:
        f.write(recipe())
    ref = os.path.join(out, recipe.__name__ + "_ref.exr")
    if not os.path.exists(ref):
        render(scene, ref, "tree", 64 * spp, 99)
    r = rgb(channels(ref))
    res = {}
    for sel in variants:
        mses, secs = [], []
        for seed in range(1, seeds + 1):
            tag = sel.replace(":", "_").replace("/", "_")
            img = os.path.join(out, f"{recipe.__name__}_{tag}_{seed}.exr")
            secs.append(render(scene, img, sel, spp, seed))
            mses.append(float(((rgb(channels(img)) - r) ** 2).mean()))
        res[sel] = (float(np.median(mses)), float(np.median(secs)))
    rows.append((recipe.__name__, res))
    u, ut = res["uniform"]
    print(f"{recipe.__name__:14s} " + "  ".join(
        f"{s}: MSE {m:.3e} ({u / m:5.2f}x) {t:5.2f} s (eff {u * ut / (m * t):5.2f}x)"
        for s, (m, t) in res.items()), flush=True)
