#!/usr/bin/env python3
"""Writes the bumpy icosphere of crates/lightpath/benches/render.rs as an OBJ (no mesh files
in git): `bumpy_sphere.py LEVELS OUT.obj` -> 20 * 4^LEVELS triangles (6: 81,920), radius
0.4 with bumps, centred in the Cornell box (Mitsuba's cornell_box() frame)."""
import math
import sys


def main():
    levels, out = int(sys.argv[1]), sys.argv[2]
    t = (1.0 + math.sqrt(5.0)) / 2.0

    def unit(p):
        n = math.sqrt(sum(c * c for c in p))
        return tuple(c / n for c in p)

    pos = [unit(p) for p in [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mids = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in mids:
                pa, pb = pos[a], pos[b]
                pos.append(unit(tuple(x + y for x, y in zip(pa, pb))))
                mids[key] = len(pos) - 1
            return mids[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    with open(out, "w") as f:
        for x, y, z in pos:
            bump = 1.0 + 0.08 * math.sin(9.0 * x) * math.sin(7.0 * y) * math.sin(8.0 * z)
            s = 0.4 * bump
            f.write(f"v {x * s:.7g} {y * s:.7g} {z * s:.7g}\n")
        for a, b, c in faces:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")
    print(f"{out}: {len(pos)} vertices, {len(faces)} triangles")


if __name__ == "__main__":
    main()
