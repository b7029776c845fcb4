#!/usr/bin/env python3
"""Held-out media check (issue 27): cornell-classic with a cube of homogeneous fog behind a
null boundary (sigma_a 0.05, sigma_s 0.6, g 0.3) and a glass ball (ior 1.5) with an
absorbing interior, rendered by Lightpath and by Mitsuba 3's volpath (llvm_ad_rgb) at the
same depth; prints the image means and the mean of the fog's and the ball's regions (their
projected bounding boxes), and the relative differences.

  python3 benches/media/compare.py --spp 256 --mitsuba-spp 1024
  python3 benches/media/compare.py --lightpath target/release/lightpath --spp 4096

The scene file it renders is written beside the outputs (out/fog_cornell.toml).

Equal time (--equal-time SPP): Lightpath renders SPP samples (beauty only, samples after
the reference's: --first-sample 4096 + run × SPP), timed by wall clock including loading;
Mitsuba renders passes (after a 1-spp render that compiles its kernels) while the next is
expected to fit in the same time (seeds from 1000); both are compared by RMSE against the
reference, the mean of the two 4096-spp renders (out/lightpath_4096spp.exr and
out/mitsuba_4096spp_<res>.exr, made by the plain mode with --spp 4096 --mitsuba-spp 4096):

  python3 benches/media/compare.py --equal-time 64 --repeat 3"""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "benches", "peer"))
import mitsuba_cornell as mc  # noqa: E402  (the cornell JSON scene, pick_libllvm, render_np)

FOG_CENTER, FOG_HALF = (-0.5, -0.64, 0.4), 0.34
FOG = dict(sigma_a=0.05, sigma_s=0.6, g=0.3)
BALL_CENTER, BALL_RADIUS = (0.33, -0.14, 0.38), 0.25
BALL_SIGMA_A = (1.6, 0.25, 1.2)
IOR = 1.5

MEDIA_TOML = f"""
[media.fog]
sigma_a = [{FOG['sigma_a']}, {FOG['sigma_a']}, {FOG['sigma_a']}]
sigma_s = [{FOG['sigma_s']}, {FOG['sigma_s']}, {FOG['sigma_s']}]
g = {FOG['g']}

[media.green]
sigma_a = [{BALL_SIGMA_A[0]}, {BALL_SIGMA_A[1]}, {BALL_SIGMA_A[2]}]

[materials.glass]
type = "dielectric"
ior = {IOR}

[[objects]]
name = "fog"
shape = "cube"
material = "null"
interior = "fog"
scale = {FOG_HALF}
translate = [{FOG_CENTER[0]}, {FOG_CENTER[1]}, {FOG_CENTER[2]}]

[[objects]]
name = "ball"
shape = "sphere"
material = "glass"
interior = "green"
radius = {BALL_RADIUS}
center = [{BALL_CENTER[0]}, {BALL_CENTER[1]}, {BALL_CENTER[2]}]

[aovs]
fog_light = "C.*<V.'fog'>.*[LO]"
"""


def lightpath_scene(path, aovs=True):
    base = open(os.path.join(ROOT, "scenes", "cornell-classic.toml")).read()
    media = MEDIA_TOML if aovs else MEDIA_TOML[:MEDIA_TOML.index("[aovs]")]
    with open(path, "w") as f:
        f.write(base + media)


def mitsuba_scene(mi, spp, max_depth, res):
    d, (w, h) = mc.load_json_scene(mi, os.path.join(ROOT, "benches", "peer", "cornell_scene.json"), spp,
                                   max_depth, 5, res)
    d["integrator"] = {"type": "volpath", "max_depth": max_depth, "rr_depth": 5}
    st = FOG["sigma_a"] + FOG["sigma_s"]
    T = mi.ScalarTransform4f
    d["shape_fog"] = {
        "type": "cube",
        "to_world": T().translate(list(FOG_CENTER)).scale(FOG_HALF),
        "bsdf": {"type": "null"},
        "interior": {"type": "homogeneous", "sigma_t": st, "albedo": FOG["sigma_s"] / st,
                     "phase": {"type": "hg", "g": FOG["g"]}},
    }
    d["shape_ball"] = {
        "type": "sphere", "center": list(BALL_CENTER), "radius": BALL_RADIUS,
        "bsdf": {"type": "dielectric", "int_ior": IOR, "ext_ior": 1.0},
        # An RGB parameter is a reflectance (at most 1) to Mitsuba: the scale carries the rest.
        "interior": {"type": "homogeneous", "scale": max(BALL_SIGMA_A),
                     "sigma_t": {"type": "rgb", "value": [c / max(BALL_SIGMA_A) for c in BALL_SIGMA_A]},
                     "albedo": 0.0},
    }
    return d, (w, h)


def project_box(lo, hi, w, h):
    """Pixel bounding box of a world box seen by cornell-classic's camera."""
    pos, fov = np.array([0.0, 0.0, 3.9]), np.radians(39.3077)
    t = np.tan(fov / 2)
    xs, ys = [], []
    for cx in (lo[0], hi[0]):
        for cy in (lo[1], hi[1]):
            for cz in (lo[2], hi[2]):
                v = np.array([cx, cy, cz]) - pos
                # The camera looks down -z with +y up.
                xs.append((v[0] / -v[2] / t + 1) / 2 * w)
                ys.append((1 - v[1] / -v[2] / t) / 2 * h)
    return int(max(min(xs), 0)), int(min(max(xs), w)), int(max(min(ys), 0)), int(min(max(ys), h))


def load(path, layer=None):
    """An EXR's beauty (its first three channels), or the RGB of AOV `layer`."""
    import mitsuba as mi
    bmp = mi.Bitmap(path)
    img = np.array(bmp).astype(np.float64)
    if layer is None:
        return img[..., :3]
    names = [f.name for f in bmp.struct_()]
    return img[..., [names.index(f"{layer}.{c}") for c in "RGB"]]


def rmse(a, b, region=None):
    if region is not None:
        x0, x1, y0, y1 = region
        a, b = a[y0:y1, x0:x1], b[y0:y1, x0:x1]
    return float(np.sqrt(np.mean((a - b) ** 2)))


def equal_time(args):
    """Lightpath at args.equal_time spp and Mitsuba at the same wall time, RMSE against the
    mean of the two 4096-spp references, args.repeat times."""
    res = (args.res, args.res)
    refs = [os.path.join(args.out, "lightpath_4096spp.exr"),
            os.path.join(args.out, f"mitsuba_4096spp_{args.res}.exr")]
    for r in refs:
        if not os.path.exists(r):
            sys.exit(f"missing reference {r}: run --spp 4096 --mitsuba-spp 4096 --res {args.res} first")
    ref = (load(refs[0]) + load(refs[1])) / 2
    w, h = res
    fog = project_box(np.array(FOG_CENTER) - FOG_HALF, np.array(FOG_CENTER) + FOG_HALF, w, h)
    toml = os.path.join(args.out, "fog_cornell_beauty.toml")
    lightpath_scene(toml, aovs=False)
    mc.pick_libllvm()
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(2)
    rows = []
    for rep in range(args.repeat):
        lp_exr = os.path.join(args.out, f"lightpath_eqt_{args.equal_time}spp.exr")
        t = time.perf_counter()
        subprocess.run([args.lightpath, "render", toml, "--spp", str(args.equal_time), "--first-sample", str(4096 + rep * args.equal_time),
                        "--max-depth", str(args.max_depth), "--resolution", f"{args.res}x{args.res}",
                        "--aovs", "none", "-o", lp_exr], check=True, stdout=subprocess.DEVNULL)
        lp_s = time.perf_counter() - t
        lp = load(lp_exr)
        # Mitsuba: the scene loaded and the kernels compiled (a 1-spp render), then its
        # time per sample from a short run, then as many samples as Lightpath's time buys.
        d, _ = mitsuba_scene(mi, 1, args.max_depth, res)
        scene = mi.load_dict(d)
        mc.render_np(mi, dr, scene, 1, 999, 0)
        probe = max(4, args.equal_time // 8)
        t = time.perf_counter()
        mc.render_np(mi, dr, scene, probe, 998, 0)
        per_spp = (time.perf_counter() - t) / probe
        # Passes of about a quarter of the budget each (every pass pays Mitsuba's fixed
        # cost per render), added while the next one is expected to fit.
        q = max(1, int(lp_s / per_spp) // 4)
        acc, m_spp, m_s, seed = None, 0, 0.0, 1000 + 100 * rep
        while m_spp == 0 or m_s + m_s / (m_spp / q) * 0.5 < lp_s:
            t = time.perf_counter()
            img = mc.render_np(mi, dr, scene, q, seed, 0)
            m_s += time.perf_counter() - t
            acc = img * q if acc is None else acc + img * q
            m_spp += q
            seed += 1
        mts = acc / m_spp
        row = dict(lp_spp=args.equal_time, lp_s=lp_s, m_spp=m_spp, m_s=m_s,
                   lp_rmse=rmse(lp, ref), m_rmse=rmse(mts, ref),
                   lp_fog=rmse(lp, ref, fog), m_fog=rmse(mts, ref, fog))
        rows.append(row)
        print(f"run {rep}: lightpath {row['lp_spp']} spp {lp_s:.1f} s RMSE {row['lp_rmse']:.5f} (fog {row['lp_fog']:.5f}); "
              f"mitsuba {m_spp} spp {m_s:.1f} s RMSE {row['m_rmse']:.5f} (fog {row['m_fog']:.5f}); "
              f"ratio lightpath/mitsuba {row['lp_rmse'] / row['m_rmse']:.3f} (fog {row['lp_fog'] / row['m_fog']:.3f})",
              flush=True)
    # Error at equal time, corrected for the time actually spent (RMSE ~ 1/sqrt(time)).
    adj = [r["lp_rmse"] / r["m_rmse"] * np.sqrt(r["lp_s"] / r["m_s"]) for r in rows]
    print(f"mean ratio {np.mean([r['lp_rmse'] / r['m_rmse'] for r in rows]):.3f}, "
          f"time-corrected {np.mean(adj):.3f} (≤ 1: Lightpath's error is at most Mitsuba's)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lightpath", default=os.path.join(ROOT, "target", "release", "lightpath"))
    ap.add_argument("--spp", type=int, default=256, help="Lightpath's samples per pixel")
    ap.add_argument("--mitsuba-spp", type=int, default=1024)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--out", default=os.path.join(HERE, "out"))
    ap.add_argument("--reuse-mitsuba", action="store_true", help="keep an existing Mitsuba image")
    ap.add_argument("--reuse-lightpath", action="store_true", help="keep an existing Lightpath image")
    ap.add_argument("--equal-time", type=int, default=0, metavar="SPP",
                    help="equal-time mode: Lightpath at SPP, Mitsuba at the same wall time, RMSE vs the reference")
    ap.add_argument("--repeat", type=int, default=1, help="equal-time runs")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.equal_time:
        return equal_time(args)
    res = (args.res, args.res)

    toml = os.path.join(args.out, "fog_cornell.toml")
    lightpath_scene(toml)
    lp_exr = os.path.join(args.out, f"lightpath_{args.spp}spp.exr")
    t = time.perf_counter()
    if not (args.reuse_lightpath and os.path.exists(lp_exr)):
        subprocess.run([args.lightpath, "render", toml, "--spp", str(args.spp), "--max-depth", str(args.max_depth),
                        "--resolution", f"{args.res}x{args.res}", "-o", lp_exr], check=True)
    lp_s = time.perf_counter() - t
    mts_exr = os.path.join(args.out, f"mitsuba_{args.mitsuba_spp}spp_{args.res}.exr")
    mts_s = float("nan")
    if not (args.reuse_mitsuba and os.path.exists(mts_exr)):
        mc.pick_libllvm()
        import drjit as dr
        import mitsuba as mi
        mi.set_variant("llvm_ad_rgb")
        dr.set_thread_count(2)
        d, _ = mitsuba_scene(mi, args.mitsuba_spp, args.max_depth, res)
        scene = mi.load_dict(d)
        t = time.perf_counter()
        img = mc.render_np(mi, dr, scene, args.mitsuba_spp, 0, min(args.mitsuba_spp, 256))
        mts_s = time.perf_counter() - t
        mi.Bitmap(img.astype(np.float32)).write(mts_exr)
    lp, mts = load(lp_exr), load(mts_exr)
    w, h = res
    lo = np.array(FOG_CENTER) - FOG_HALF
    hi = np.array(FOG_CENTER) + FOG_HALF
    regions = {"image": (0, w, 0, h), "fog": project_box(lo, hi, w, h),
               "ball": project_box(np.array(BALL_CENTER) - BALL_RADIUS, np.array(BALL_CENTER) + BALL_RADIUS, w, h)}
    print(f"lightpath {args.spp} spp {lp_s:.1f} s; mitsuba volpath llvm_ad_rgb {args.mitsuba_spp} spp {mts_s:.1f} s")
    for name, (x0, x1, y0, y1) in regions.items():
        a = lp[y0:y1, x0:x1].reshape(-1, 3).mean(0)
        b = mts[y0:y1, x0:x1].reshape(-1, 3).mean(0)
        rel = (a - b) / b
        if name == "fog":
            # The fog's own light, `C.*<V.'fog'>.*[LO]`, and how much of the region it is.
            fl = load(lp_exr, "fog_light")[y0:y1, x0:x1].reshape(-1, 3).mean(0)
            print(f"   fog_light AOV in the fog's region {np.round(fl, 4).tolist()} = "
                  f"{np.round(100 * fl / a, 1).tolist()} % of it")
        print(f"{name:>6} px[{x0}:{x1}, {y0}:{y1}]  lightpath {np.round(a, 4).tolist()}  mitsuba "
              f"{np.round(b, 4).tolist()}  rel diff {np.round(100 * rel, 2).tolist()} %  (mean of channels "
              f"{100 * (a.mean() - b.mean()) / b.mean():+.2f} %)")


if __name__ == "__main__":
    main()
