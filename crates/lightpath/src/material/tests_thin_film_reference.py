"""Reference values for tests_thin_film.rs::matches_an_independent_spectral_integration.

Independent of the renderer's method (Belcour & Barla 2017's Fourier series cut after
three orders, over a tabulated transform of the sensitivities): the exact Airy
reflectance of the film, per polarisation and wavelength,
|(r12 + r23 e^{i delta}) / (1 + r12 r23 e^{i delta})|^2, integrated by quadrature over
wavelength (0.1 nm steps, the CIE data linearly interpolated) against the CIE 1931
colour-matching functions (cie1931_2deg.csv) converted to linear Rec.709 sensitivities,
each normalised to unit area (a flat reflectance R gives (R, R, R)).

A metal given by its F82 colours ("f82" below) reflects at the film with the strength of
the F82 model (F0 of its Gulbrandsen index seen from the film, the F82 colour as given)
and the phase of that index, as thin_film.rs's FilmBase::F82 describes.

Run: python3 tests_thin_film_reference.py   (standard library only, f64)
"""

import cmath
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
CMF = [[float(v) for v in line.split(",")]
       for line in open(os.path.join(HERE, "cie1931_2deg.csv"))
       if line[:1].isdigit()]


def xyz_of(x, y):
    return [x / y, 1.0, (1.0 - x - y) / y]


def inv3(m):
    a, b, c = m[0]
    d, e, f = m[1]
    g, h, i = m[2]
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return [
        [(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det],
        [(f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det],
        [(d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det],
    ]


# Rec.709 primaries and D65 white (IEC 61966-2-1): XYZ (Y = 1 white) -> linear RGB.
PRIMARIES = [xyz_of(0.64, 0.33), xyz_of(0.30, 0.60), xyz_of(0.15, 0.06)]
WHITE = xyz_of(0.3127, 0.3290)
P = [[PRIMARIES[j][i] for j in range(3)] for i in range(3)]
S = [sum(inv3(P)[i][k] * WHITE[k] for k in range(3)) for i in range(3)]
XYZ_TO_RGB = inv3([[P[i][j] * S[j] for j in range(3)] for i in range(3)])

# Quadrature nodes: wavelength and the three RGB sensitivities, unnormalised.
NODES = []
for k in range(len(CMF) - 1):
    lo, hi = CMF[k], CMF[k + 1]
    for j in range(10):
        t = (j + 0.5) / 10
        wl = lo[0] + t * (hi[0] - lo[0])
        xyz = [lo[i] + t * (hi[i] - lo[i]) for i in (1, 2, 3)]
        NODES.append((wl, [sum(XYZ_TO_RGB[c][i] * xyz[i] for i in range(3)) for c in range(3)]))
NORM = [sum(s[c] for _, s in NODES) for c in range(3)]


def amplitudes(n1, n2, cos1):
    """Fresnel amplitudes (s, p) from n1 into complex n2, and the cosine in n2."""
    c2 = cmath.sqrt(1 - (n1 / n2) ** 2 * (1 - cos1 * cos1))
    if (n2 * c2).imag < 0:
        c2 = -c2
    rs = (n1 * cos1 - n2 * c2) / (n1 * cos1 + n2 * c2)
    rp = (n2 * cos1 - n1 * c2) / (n2 * cos1 + n1 * c2)
    return rs, rp, c2


def f82_model(cos, f0, f82):
    """Schlick's curve less b cos (1 - cos)^6, b such that it passes f82 at cos 1/7."""
    schlick = lambda mu: f0 + (1 - f0) * (1 - mu) ** 5
    b = (schlick(1 / 7) - f82) / ((1 / 7) * (6 / 7) ** 6)
    return min(max(schlick(cos) - b * cos * (1 - cos) ** 6, 0.0), 1.0)


def gulbrandsen(r, g):
    r = min(max(r, 0.0), 0.99)
    n = g * (1 - r) / (1 + r) + (1 - g) * (1 + math.sqrt(r)) / (1 - math.sqrt(r))
    k = math.sqrt(max((r * (n + 1) ** 2 - (n - 1) ** 2) / (1 - r), 0.0))
    return complex(n, k)


def rgb_channel(cos1, n1, n2, d_nm, n3, c, f82=None):
    """Channel c of the film's reflectance over a base of complex index n3; with f82 the
    base reflects with the F82 model's strength at the film's angle."""
    rs12, rp12, c2 = amplitudes(n1, complex(n2), cos1)
    c2 = c2.real
    rs23, rp23, _ = amplitudes(n2, n3, c2)
    if f82 is not None:
        f0 = abs((n3 - n2) / (n3 + n2)) ** 2
        strength = math.sqrt(f82_model(c2, f0, f82))
        rs23 = strength * cmath.exp(1j * cmath.phase(rs23))
        rp23 = strength * cmath.exp(1j * cmath.phase(rp23))
    out = 0.0
    for wl, s in NODES:
        e = cmath.exp(1j * 2 * math.pi * (2 * n2 * d_nm * c2) / wl)
        r = sum(0.5 * abs((r12 + r23 * e) / (1 + r12 * r23 * e)) ** 2
                for r12, r23 in ((rs12, rs23), (rp12, rp23)))
        out += s[c] * r
    return out / NORM[c]


def rgb(cos1, outside, film, d_nm, base):
    if base[0] == "dielectric":
        return [rgb_channel(cos1, outside, film, d_nm, complex(base[1]), c) for c in range(3)]
    if base[0] == "conductor":
        eta, kappa = base[1], base[2]
        return [rgb_channel(cos1, outside, film, d_nm, complex(eta[c], kappa[c]), c)
                for c in range(3)]
    f0, f82 = base[1], base[2]
    return [rgb_channel(cos1, outside, film, d_nm, gulbrandsen(f0[c], f82[c]), c, f82[c])
            for c in range(3)]


CASES = [
    (0.8, 1.0, 1.33, 300, ("dielectric", 1.5)),
    (0.3, 1.0, 1.8, 500, ("dielectric", 1.5)),
    (0.6, 1.0, 1.4, 400, ("conductor", (0.2, 0.9, 1.1), (3.0, 2.5, 2.2))),
    (0.9, 1.5, 2.0, 250, ("dielectric", 1.3)),
    (1.0, 1.0, 1.3, 650, ("conductor", (0.18, 0.42, 1.37), (3.42, 2.35, 1.77))),
    (0.7, 1.0, 1.6, 900, ("f82", (0.9, 0.6, 0.3), (0.8, 0.7, 0.5))),
    # tests_thin_film.rs::metal_film_follows_the_f82_reflectance: f0 0.05, F82 tint 1.
    (1.0, 1.0, 1.33, 400, ("f82", (0.05,) * 3, (0.4895311,) * 3)),
    (0.5, 1.0, 1.33, 400, ("f82", (0.05,) * 3, (0.4895311,) * 3)),
]

if __name__ == "__main__":
    print("XYZ -> RGB:", [["%.7f" % v for v in row] for row in XYZ_TO_RGB])
    for cos1, outside, film, d, base in CASES:
        print(cos1, outside, film, d, base, ["%.6f" % v for v in rgb(cos1, outside, film, d, base)])
