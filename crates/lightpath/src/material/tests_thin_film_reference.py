"""Reference values for tests_thin_film.rs::matches_an_independent_spectral_integration.

Independent of the renderer's method (Belcour & Barla 2017's Fourier series cut after
three orders): the exact Airy reflectance of the film, per polarisation and wavenumber,
|(r12 + r23 e^{i delta}) / (1 + r12 r23 e^{i delta})|^2, integrated by quadrature over
wavenumber against the paper's Gaussian fit of the CIE XYZ sensitivities (the densities
whose Fourier transforms the paper's code evaluates), normalised so a flat reflectance R
gives XYZ = (R, R, R), scaled to the D65 white and converted to linear Rec.709.

Run: python3 tests_thin_film_reference.py   (standard library only, f64)
"""

import cmath
import math

# The paper's fit, per lobe: (channel, val, pos [1/m], var [1/m^2]); its code evaluates
# val * sqrt(2 pi var) * cos(pos t + shift) * exp(-var t^2) at t = 2 pi OPD, the Fourier
# transform of the density val / sqrt(2) * exp(-(nu - pos)^2 / (4 var)) in wavenumber nu.
LOBES = [
    (0, 5.4856e-13, 1.6810e06, 4.3278e09),
    (1, 4.4201e-13, 1.7953e06, 9.3046e09),
    (2, 5.2481e-13, 2.2084e06, 6.6121e09),
    (0, 9.7470e-14, 2.2399e06, 4.5282e09),
]


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


# Rec.709 primaries and D65 white (IEC 61966-2-1).
PRIMARIES = [xyz_of(0.64, 0.33), xyz_of(0.30, 0.60), xyz_of(0.15, 0.06)]
WHITE = xyz_of(0.3127, 0.3290)
P = [[PRIMARIES[j][i] for j in range(3)] for i in range(3)]
S = [sum(inv3(P)[i][k] * WHITE[k] for k in range(3)) for i in range(3)]
XYZ_TO_RGB = inv3([[P[i][j] * S[j] for j in range(3)] for i in range(3)])
# E white (1, 1, 1) scaled to D65, then to RGB.
M = [[XYZ_TO_RGB[i][j] * WHITE[j] for j in range(3)] for i in range(3)]


def amplitudes(n1, n2, cos1):
    """Fresnel amplitudes (s, p) from n1 into complex n2, and the cosine in n2."""
    c2 = cmath.sqrt(1 - (n1 / n2) ** 2 * (1 - cos1 * cos1))
    if (n2 * c2).imag < 0:
        c2 = -c2
    rs = (n1 * cos1 - n2 * c2) / (n1 * cos1 + n2 * c2)
    rp = (n2 * cos1 - n1 * c2) / (n2 * cos1 + n1 * c2)
    return rs, rp, c2


def airy(cos1, n1, n2, d_nm, n3, nu):
    rs12, rp12, c2 = amplitudes(n1, complex(n2), cos1)
    c2 = c2.real
    rs23, rp23, _ = amplitudes(n2, n3, c2)
    e = cmath.exp(1j * 2 * math.pi * (2 * n2 * d_nm * 1e-9 * c2) * nu)
    return sum(0.5 * abs((r12 + r23 * e) / (1 + r12 * r23 * e)) ** 2
               for r12, r23 in ((rs12, rs23), (rp12, rp23)))


def xyz(cos1, n1, n2, d_nm, n3, steps=4000):
    out, norm = [0.0] * 3, [0.0] * 3
    for c, val, pos, var in LOBES:
        sigma = math.sqrt(2 * var)
        lo, hi = pos - 10 * sigma, pos + 10 * sigma
        h = (hi - lo) / steps
        for k in range(steps):
            nu = lo + (k + 0.5) * h
            g = val * math.exp(-((nu - pos) ** 2) / (4 * var)) * h
            out[c] += g * airy(cos1, n1, n2, d_nm, n3, nu)
            norm[c] += g
    return [out[i] / norm[i] for i in range(3)]


def rgb(cos1, outside, film, d_nm, base):
    if base[0] == "dielectric":
        x = xyz(cos1, outside, film, d_nm, complex(base[1]))
        return [sum(M[i][j] * x[j] for j in range(3)) for i in range(3)]
    eta, kappa = base[1], base[2]
    out = []
    for c in range(3):
        x = xyz(cos1, outside, film, d_nm, complex(eta[c], kappa[c]))
        out.append(sum(M[c][j] * x[j] for j in range(3)))
    return out


CASES = [
    (0.8, 1.0, 1.33, 300, ("dielectric", 1.5)),
    (0.3, 1.0, 1.8, 500, ("dielectric", 1.5)),
    (0.6, 1.0, 1.4, 400, ("conductor", (0.2, 0.9, 1.1), (3.0, 2.5, 2.2))),
    (0.9, 1.5, 2.0, 250, ("dielectric", 1.3)),
    (1.0, 1.0, 1.3, 650, ("conductor", (0.18, 0.42, 1.37), (3.42, 2.35, 1.77))),
    # tests_thin_film.rs::metal_film_follows_the_f82_reflectance: f0 0.05, F82 tint 1.
    (1.0, 1.0, 1.33, 400, ("conductor", (1.2474,) * 3, (0.4488,) * 3)),
]

if __name__ == "__main__":
    print("XYZ -> RGB (E white):", [["%.7f" % v for v in row] for row in M])
    for cos1, outside, film, d, base in CASES:
        print(cos1, outside, film, d, base, ["%.6f" % v for v in rgb(cos1, outside, film, d, base)])
