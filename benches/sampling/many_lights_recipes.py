"""The recipes of the many-light set (issue 29), as renderer-neutral scene descriptions.

Shared by many_lights_set.py (Lightpath's light selections) and many_lights_peers.py
(Lightpath against Mitsuba 3 and Cycles). A recipe draws its placements from the global
`random` (seeded with the recipe's name by `build`) and returns a plain dict (JSON-safe):

    {"name", "camera": {"position", "look_at", "fov"}, "max_depth", "rr_depth",
     "materials": {name: {"type": "diffuse", "albedo"} | {"type": "conductor", "f0", "roughness"}},
     "objects": [{"name", "shape": "quad" (corners) | "cube" (scale, rotate, translate)
                  | "sphere" (center, radius), "material"}],
     "lights": [{"type": "sphere" (center, radius, radiance) | "rect" (radiance, rotate,
                 translate, scale; emits on its +z side) | "point" (position, intensity)
                 | "spot" (position, direction, cone_angle, cone_softness, intensity)
                 | "distant" (direction, irradiance) | "dome" (radiance),
                 "name"?, "groups"?, "camera_visible"?}]}

with Lightpath's TOML meanings (docs/scene-format.md): a rotate is degrees about X, then Y,
then Z (right-handed), applied after the scale and before the translate. Numbers are
rounded as the TOML prints them, so every renderer sees the same scene. `to_toml` writes
the Lightpath scene; `matrix` gives a placement's 4x4 (row-major) for the other renderers.
"""

import math
import os
import random


def room(w=10.0, d=8.0, h=4.0, camera=((0, 2.2, 6.5), (0, 0.6, 0))):
    position, look_at = camera
    return {
        "camera": {"position": list(position), "look_at": list(look_at), "fov": 50.0},
        "max_depth": 6,
        "rr_depth": 4,
        "materials": {
            "floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "wall": {"type": "diffuse", "albedo": [0.6, 0.55, 0.5]},
            "blue": {"type": "diffuse", "albedo": [0.2, 0.3, 0.7]},
            "metal": {"type": "conductor", "f0": [0.9, 0.9, 0.9], "roughness": 0.3},
        },
        "objects": [
            {"name": "floor", "shape": "quad", "material": "floor",
             "corners": [[-w / 2, 0, d / 2], [w / 2, 0, d / 2], [w / 2, 0, -d / 2], [-w / 2, 0, -d / 2]]},
            {"name": "backWall", "shape": "quad", "material": "wall",
             "corners": [[-w / 2, 0, -d / 2], [w / 2, 0, -d / 2], [w / 2, h, -d / 2], [-w / 2, h, -d / 2]]},
            {"name": "box", "shape": "cube", "material": "blue", "scale": [0.5, 0.5, 0.5],
             "rotate": [0, 30, 0], "translate": [-1.2, 0.5, -0.5]},
            {"name": "ball", "shape": "sphere", "material": "metal", "center": [1.2, 0.6, 0.2], "radius": 0.6},
        ],
        "lights": [],
    }


def lamp(x, y, z, power, r=0.04):
    rgb = [power * c for c in random.choice([(1, .5, .2), (.3, 1, .3), (.2, .4, 1), (1, .9, .8)])]
    return {"type": "sphere", "groups": ["lamps"], "camera_visible": False,
            "center": [round(x, 3), round(y, 3), round(z, 3)], "radius": r,
            "radiance": [round(c, 2) for c in rgb]}


def dome(v=0.03):
    return {"type": "dome", "name": "sky", "radiance": [v, round(v * 1.3, 3), round(v * 2, 3)]}


def sky_key_lamps():
    s = room()
    s["lights"] += [dome(),
                    {"type": "distant", "name": "sun", "direction": [0.4, -1, -0.3], "irradiance": [2.0, 1.8, 1.5]},
                    {"type": "point", "name": "bulb", "position": [2.5, 2.5, 1.0], "intensity": [4, 4, 4]}]
    for _ in range(24):
        s["lights"].append(lamp(random.uniform(-4, 4), random.uniform(0.2, 2.5), random.uniform(-3.5, 3),
                                10 ** random.uniform(0.5, 2.5)))
    return s


def clusters():
    s = room()
    s["lights"].append(dome(0.01))
    for cx, cz, power in ((-3, 2, 20), (3, 1, 20), (0, -3.5, 400)):
        for _ in range(16):
            s["lights"].append(lamp(cx + random.gauss(0, 0.4), random.uniform(0.3, 1.5),
                                    cz + random.gauss(0, 0.3), power))
    return s


def ceiling_grid():
    s = room()
    s["lights"].append(dome(0.02))
    for i in range(8):
        for j in range(5):
            x, z = -3.5 + i, -3 + 1.4 * j
            p = 10 ** random.uniform(0, 1.3)
            s["lights"].append({"type": "rect", "groups": ["panels"], "camera_visible": False,
                                "radiance": [round(p, 2), round(p, 2), round(p * 0.9, 2)],
                                "rotate": [90, 0, 0], "translate": [x, 3.9, z], "scale": [0.15, 0.15, 1]})
    return s


def spots():
    s = room()
    s["lights"].append(dome(0.02))
    for _ in range(20):
        x, y, z = random.uniform(-4, 4), random.uniform(2.5, 3.8), random.uniform(-3, 3)
        tx, tz = random.uniform(-4, 4), random.uniform(-3.5, 3.5)
        p = round(10 ** random.uniform(0.5, 1.5), 2)
        s["lights"].append({"type": "spot", "groups": ["spots"],
                            "position": [round(x, 2), round(y, 2), round(z, 2)],
                            "direction": [round(tx - x, 2), round(-y, 2), round(tz - z, 2)],
                            "cone_angle": round(random.uniform(15, 50), 1), "cone_softness": 5,
                            "intensity": [p, p, p]})
    return s


def two_big_many():
    s = room()
    for x in (-2.5, 2.5):
        s["lights"].append({"type": "rect", "groups": ["big"], "radiance": [12, 11, 10], "rotate": [90, 0, 0],
                            "translate": [x, 3.9, 0], "scale": [0.5, 0.5, 1], "camera_visible": False})
    for _ in range(60):
        s["lights"].append(lamp(random.uniform(-4.5, 4.5), random.uniform(0.1, 0.6), random.uniform(-3.5, 3.5),
                                10 ** random.uniform(0.3, 1.3), r=0.02))
    return s


def corridor():
    s = room(w=3.0, d=30.0, h=3.0, camera=((0, 1.6, 14.5), (0, 1.2, 0)))
    s["lights"].append(dome(0.005))
    for i in range(30):
        z = 14 - i
        s["lights"].append(lamp(random.choice((-1.3, 1.3)), 2.6, z, 10 ** random.uniform(1, 2)))
    return s


def tuned_many_lights():
    """scenes/many-lights.toml, the scene the tree was tuned on (lamps hidden, as above);
    Lightpath only (a TOML text, not a description)."""
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "..", "scenes", "many-lights.toml")) as f:
        text = f.read()
    return {"toml": text.replace('groups = ["lamps"]\n', 'groups = ["lamps"]\ncamera_visible = false\n')}


RECIPES = [sky_key_lamps, clusters, ceiling_grid, spots, two_big_many, corridor, tuned_many_lights]


def build(recipe):
    """The description of `recipe` (a function of RECIPES, or its name), with its name."""
    if isinstance(recipe, str):
        recipe = {r.__name__: r for r in RECIPES}[recipe]
    random.seed(recipe.__name__)
    desc = recipe()
    desc["name"] = recipe.__name__
    return desc


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return repr(v)


def _table(header, d, skip=()):
    return f"{header}\n" + "".join(f"{k} = {_value(v)}\n" for k, v in d.items() if k not in skip) + "\n"


def to_toml(desc):
    """The Lightpath TOML scene of a description."""
    if "toml" in desc:
        return desc["toml"]
    s = _table("[camera]", desc["camera"])
    s += _table("[render]", {"max_depth": desc["max_depth"], "rr_depth": desc["rr_depth"]})
    for name, m in desc["materials"].items():
        s += _table(f"[materials.{name}]", m)
    for o in desc["objects"]:
        s += _table("[[objects]]", o)
    for light in desc["lights"]:
        s += _table("[[lights]]", light)
    return s


def matrix(scale=(1, 1, 1), rotate=(0, 0, 0), translate=(0, 0, 0)):
    """Lightpath's placement as a row-major 4x4: scale, then rotate about X, Y, Z (degrees,
    right-handed), then translate."""
    def mul(a, b):
        return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]

    def rot(axis, deg):
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        m = [[float(r == k) for k in range(4)] for r in range(4)]
        m[i][i], m[i][j], m[j][i], m[j][j] = c, -s, s, c
        return m

    sc = [[0.0] * 4 for _ in range(4)]
    for i in range(3):
        sc[i][i] = float(scale[i])
    sc[3][3] = 1.0
    m = mul(rot(2, rotate[2]), mul(rot(1, rotate[1]), mul(rot(0, rotate[0]), sc)))
    for i in range(3):
        m[i][3] = float(translate[i])
    return m
