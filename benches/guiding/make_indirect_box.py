#!/usr/bin/env python3
"""Writes the held-out guiding benchmark scene, the indirect-only box: Mitsuba's Cornell
box (../peer/cornell_scene.json) with its lamp turned to face the ceiling and a baffle
under it, so the room sees no lamp and every path to the light bounces off the ceiling
(or the baffle's top is never lit: the lamp emits upwards only). Same renderer-neutral
JSON as the peer scene, so ../peer/mitsuba_cornell.py --json renders it in Mitsuba 3 and
../peer/make_cornell_classic.py turns it into a Lightpath scene:

    python3 benches/guiding/make_indirect_box.py > benches/guiding/indirect_box.json
    python3 benches/peer/make_cornell_classic.py benches/guiding/indirect_box.json \
        > benches/guiding/indirect_box.toml
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def quad(corners):
    c = corners
    return {"corners": c, "triangles": [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]}


def normal(c):
    a = [c[1][i] - c[0][i] for i in range(3)]
    b = [c[2][i] - c[0][i] for i in range(3)]
    n = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    length = sum(x * x for x in n) ** 0.5
    return [x / length for x in n]


def obj(name, material, quads, emitter=None):
    o = {"name": name, "material": material, "quads": [], "triangles": []}
    for c in quads:
        q = quad(c)
        o["quads"].append({"corners": c, "normal": normal(c)})
        o["triangles"] += q["triangles"]
    if emitter:
        o["emitter"] = emitter
    return o


js = json.load(open(os.path.join(HERE, "..", "peer", "cornell_scene.json")))
js["name"] = "indirect-only box (benches/guiding/make_indirect_box.py)"
lamp = next(o for o in js["objects"] if "emitter" in o)
js["objects"] = [o for o in js["objects"] if "emitter" not in o]
y_lamp, y_top, y_bottom, b = 0.80, 0.795, 0.79, 0.40
# The lamp: the peer's quad, lowered and wound to face +y (the ceiling).
x0, x1, z0, z1 = -0.23, 0.23, -0.18, 0.2
js["objects"].append(obj("light", "white",
                         [[[x0, y_lamp, z0], [x0, y_lamp, z1], [x1, y_lamp, z1], [x1, y_lamp, z0]]],
                         lamp["emitter"]))
# The baffle: a square under the lamp, a face up and a face down (BSDFs are one-sided).
js["objects"].append(obj("baffle", "white", [
    [[-b, y_top, -b], [-b, y_top, b], [b, y_top, b], [b, y_top, -b]],
    [[-b, y_bottom, -b], [b, y_bottom, -b], [b, y_bottom, b], [-b, y_bottom, b]],
]))
json.dump(js, sys.stdout, indent=1)
sys.stdout.write("\n")
