#!/usr/bin/env python3
"""Mitsuba 3 peer renderer for the Cornell box.

Two scene sources:
  --scene json     (default) rebuild the scene from cornell_scene.json: world-space
                   triangles, one-sided diffuse BSDFs, one-sided area emitter, box
                   pixel filter -- the renderer-neutral description other renderers
                   (Cycles, the Rust path tracer) reproduce.
  --scene builtin  Mitsuba's own mi.cornell_box() dict (rectangles/cubes, gaussian
                   pixel filter), only with spp / max_depth / resolution overridden.

Examples (2 threads):
  python3 mitsuba_cornell.py --variant llvm_ad_rgb --spp 64 --max-depth 8
  python3 mitsuba_cornell.py --variant scalar_rgb --spp 256 --repeat 2
  python3 mitsuba_cornell.py --spp 65536 --pass-spp 256 --seed 1000000 --out ref/cornell_ref
  python3 mitsuba_cornell.py --spp 256 --aov --lpe-split

Timing output: load time, then for each repeat the render wall time (for LLVM the
first repeat includes JIT kernel compilation, unless the kernel is in Dr.Jit's
on-disk cache from an earlier process) and samples/second = width*height*spp / time.
"""
import argparse
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))  # copied from shared/peers; reads cornell_scene.json beside it


def pick_libllvm():
    """Dr.Jit needs LLVM >= 15 and fails on Debian 12's LLVM 15 ('Cannot select:
    fminimum'); prefer a newer libLLVM if it is installed (apt-get install libllvm19)."""
    if "DRJIT_LIBLLVM_PATH" in os.environ:
        return
    for cand in ("/usr/lib/x86_64-linux-gnu/libLLVM.so.22.1", "/usr/lib/x86_64-linux-gnu/libLLVM-22.so",
                 "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"):
        if os.path.exists(cand):
            os.environ["DRJIT_LIBLLVM_PATH"] = cand
            return


def parse():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variant", default="llvm_ad_rgb", choices=["scalar_rgb", "llvm_ad_rgb", "scalar_spectral", "llvm_ad_spectral"])
    ap.add_argument("--scene", default="json", choices=["json", "builtin"])
    ap.add_argument("--json", default=os.path.join(HERE, "cornell_scene.json"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--rr-depth", type=int, default=5, help="Russian roulette start depth (Mitsuba default 5)")
    ap.add_argument("--res", type=int, nargs=2, default=None, metavar=("W", "H"), help="override resolution")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--pass-spp", type=int, default=0,
                    help="split the render into passes of this many spp (seeds seed, seed+1, ...) and average; "
                         "bounds LLVM wavefront memory for high spp. 0 = single pass")
    ap.add_argument("--repeat", type=int, default=1, help="render this many times (timing; last image is saved)")
    ap.add_argument("--out", default=None, help="output prefix (default out/cornell_<variant>_<spp>spp); "
                                                "writes PREFIX.exr and PREFIX.png")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--extra-obj", default=None, help="add this OBJ (white diffuse, flat shading) to the json scene")
    ap.add_argument("--obj-to-world", type=float, nargs=4, default=[6.0, 0.1, -1.198, 0.0], metavar=("S", "TX", "TY", "TZ"),
                    help="uniform scale then translation of --extra-obj")
    ap.add_argument("--aov", action="store_true", help="also render the 'aov' integrator (albedo, normal, depth, position) "
                                                      "next to the path image into PREFIX_aov.exr")
    ap.add_argument("--lpe-split", action="store_true",
                    help="also write PREFIX_lpe.exr with emission (max_depth=1), direct (depth<=2 minus emission) and "
                         "indirect (full minus depth<=2) layers, each rendered with the same seed(s)")
    return ap.parse_args()


def load_json_scene(mi, path, spp, max_depth, rr_depth, res):
    """Load cornell_scene.json as a Mitsuba scene made of triangle meshes."""
    import numpy as np
    with open(path) as f:
        js = json.load(f)
    cam = js["camera"]
    film = js["film"]
    W, H = res if res else (film["width"], film["height"])
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth},
        "sensor": {
            "type": "perspective",
            "fov": cam["fov_deg"],
            "fov_axis": cam.get("fov_axis", "smaller"),
            "near_clip": cam.get("near_clip", 1e-3),
            "far_clip": cam.get("far_clip", 1e4),
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["position"], target=cam["look_at"], up=cam["up"]),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": W, "height": H, "pixel_format": "rgb",
                     "component_format": "float32", "rfilter": {"type": film.get("pixel_filter", "box")}},
        },
    }
    bsdfs = {}
    for name, m in js["materials"].items():
        assert m["type"] == "diffuse", "only diffuse materials are described"
        bsdfs[name] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["albedo"]}}
    tmpdir = os.path.join(tempfile.gettempdir(), "mitsuba_cornell_ply")
    os.makedirs(tmpdir, exist_ok=True)
    for obj in js["objects"]:
        verts = np.array([v for t in obj["triangles"] for v in t], dtype=np.float32)
        faces = np.arange(len(verts), dtype=np.uint32).reshape(-1, 3)
        ply = os.path.join(tmpdir, obj["name"] + ".ply")
        write_ply(ply, verts, faces)
        s = {"type": "ply", "filename": ply, "face_normals": True, "bsdf": bsdfs[obj["material"]]}
        if "emitter" in obj:
            e = obj["emitter"]
            assert e["type"] == "area" and not e.get("two_sided", False)
            s["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": e["radiance"]}}
        d["shape_" + obj["name"]] = s
    return d, (W, H)


def write_ply(path, verts, faces):
    """Binary little-endian PLY with positions only (flat shading, winding kept)."""
    import numpy as np
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar uint vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(verts, dtype="<f4").tobytes())
        rec = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<u4", (3,))])
        rec["n"] = 3
        rec["i"] = faces
        f.write(rec.tobytes())


def load_builtin_scene(mi, spp, max_depth, rr_depth, res):
    d = mi.cornell_box()
    d["integrator"] = {"type": "path", "max_depth": max_depth, "rr_depth": rr_depth}
    d["sensor"]["sampler"]["sample_count"] = spp
    if res:
        d["sensor"]["film"]["width"], d["sensor"]["film"]["height"] = res
    W, H = d["sensor"]["film"]["width"], d["sensor"]["film"]["height"]
    return d, (W, H)


def render_np(mi, dr, scene, spp, seed, pass_spp, integrator=None):
    """Render and return a float64 numpy image (forces evaluation for timing)."""
    import numpy as np
    if pass_spp and pass_spp < spp:
        assert spp % pass_spp == 0, "--spp must be a multiple of --pass-spp"
        n = spp // pass_spp
        acc = None
        for i in range(n):
            img = mi.render(scene, spp=pass_spp, seed=seed + i, integrator=integrator)
            a = np.array(img, dtype=np.float64)
            acc = a if acc is None else acc + a
        return acc / n
    img = mi.render(scene, spp=spp, seed=seed, integrator=integrator)
    return np.array(img, dtype=np.float64)


def main():
    args = parse()
    if args.variant.startswith("llvm"):
        pick_libllvm()
    import numpy as np
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)

    t0 = time.perf_counter()
    if args.scene == "json":
        d, (W, H) = load_json_scene(mi, args.json, args.spp, args.max_depth, args.rr_depth, args.res)
    else:
        d, (W, H) = load_builtin_scene(mi, args.spp, args.max_depth, args.rr_depth, args.res)
    if args.extra_obj:
        sc, tx, ty, tz = args.obj_to_world
        d["shape_extra_obj"] = {"type": "obj", "filename": os.path.abspath(args.extra_obj), "face_normals": True,
                                "to_world": mi.ScalarTransform4f().translate([tx, ty, tz]).scale(sc),
                                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}}}
    scene = mi.load_dict(d)
    t_load = time.perf_counter() - t0

    print(f"mitsuba {mi.__version__} drjit {dr.__version__} variant={args.variant} threads={dr.thread_count()} "
          f"scene={args.scene} res={W}x{H} spp={args.spp} max_depth={args.max_depth} rr_depth={args.rr_depth} "
          f"pass_spp={args.pass_spp or args.spp}")
    print(f"load_s={t_load:.3f}")
    nsamples = W * H * args.spp
    img = None
    times, cpus = [], []
    for r in range(args.repeat):
        t, c = time.perf_counter(), time.process_time()
        img = render_np(mi, dr, scene, args.spp, args.seed + 1000 * r, args.pass_spp)
        dt = time.perf_counter() - t
        times.append(dt)
        cpus.append(time.process_time() - c)  # all threads' CPU seconds (JIT included)
        print(f"run={r} render_s={dt:.3f} samples_per_s={nsamples / dt:.4g} Msamples_per_s={nsamples / dt / 1e6:.3f}")
    best = min(times)
    print(f"RESULT variant={args.variant} spp={args.spp} max_depth={args.max_depth} threads={args.threads} "
          f"first_s={times[0]:.3f} best_s={best:.3f} best_cpu_s={cpus[times.index(best)]:.3f} "
          f"Msamples_per_s_best={nsamples / best / 1e6:.3f} mean_rgb={img.reshape(-1, 3).mean(0).round(5).tolist()}")

    if args.no_write:
        return
    prefix = args.out or os.path.join(HERE, "out", f"cornell_{args.scene}_{args.variant}_{args.spp}spp_d{args.max_depth}")
    os.makedirs(os.path.dirname(os.path.abspath(prefix)), exist_ok=True)
    bmp = mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.write(prefix + ".exr")
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(prefix + ".png")
    print("wrote", prefix + ".exr", prefix + ".png")

    if args.aov:
        aov = mi.load_dict({"type": "aov",
                            "aovs": "albedo:albedo,nn:sh_normal,dd:depth,pp:position",
                            "img": {"type": "path", "max_depth": args.max_depth, "rr_depth": args.rr_depth}})
        t = time.perf_counter()
        # aov integrator output: channels R,G,B,(A), then albedo.RGB, nn.XYZ, dd.T, pp.XYZ
        a = render_np(mi, dr, scene, args.spp, args.seed, args.pass_spp, integrator=aov)
        print(f"aov render_s={time.perf_counter() - t:.3f} channels={a.shape[-1]}")
        names = ["R", "G", "B"] + (["A"] if a.shape[-1] == 16 else []) + \
                ["albedo.R", "albedo.G", "albedo.B", "nn.X", "nn.Y", "nn.Z", "dd.Y", "pp.X", "pp.Y", "pp.Z"]
        assert len(names) == a.shape[-1], (names, a.shape)
        mi.Bitmap(a.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.MultiChannel,
                  channel_names=names).write(prefix + "_aov.exr")
        print("wrote", prefix + "_aov.exr")

    if args.lpe_split:
        layers = {}
        t = time.perf_counter()
        for depth in (1, 2):
            integ = mi.load_dict({"type": "path", "max_depth": depth, "rr_depth": args.rr_depth})
            layers[depth] = render_np(mi, dr, scene, args.spp, args.seed, args.pass_spp, integrator=integ)
        full = img
        emission = layers[1]                 # LPE  C L        (emitters seen directly)
        direct = layers[2] - layers[1]       # LPE  C <RD> L   (all BSDFs are diffuse here)
        indirect = full - layers[2]          # LPE  C <RD> <RD>+ L, up to max_depth segments
        print(f"lpe-split render_s={time.perf_counter() - t:.3f} mean emission={emission.reshape(-1, 3).mean(0).round(5).tolist()} "
              f"direct={direct.reshape(-1, 3).mean(0).round(5).tolist()} indirect={indirect.reshape(-1, 3).mean(0).round(5).tolist()}")
        chans, names = [], []
        for lname, L in (("combined", full), ("emission", emission), ("direct", direct), ("indirect", indirect)):
            chans.append(L)
            names += [f"{lname}.R", f"{lname}.G", f"{lname}.B"]
        stack = np.concatenate(chans, axis=-1).astype(np.float32)
        mi.Bitmap(stack, pixel_format=mi.Bitmap.PixelFormat.MultiChannel, channel_names=names).write(prefix + "_lpe.exr")
        print("wrote", prefix + "_lpe.exr")


if __name__ == "__main__":
    sys.exit(main())
