"""Issue 29, "held-out real scenes": Lightpath against Blender Cycles on Blender glTF shots
(a textured crate, a glass ball, a chrome ball, point, spot and sun lights), each renderer's
error measured against its own converged image.

    /work/venv311/bin/python benches/peer/real_scenes.py OUT_DIR LIGHTPATH_BINARY
        [--spp 64] [--ref-spp 4096] [--seeds 3] [--scenes shot_a,shot_b,heldout]
        [--clamp-indirect 0] [--filter-glossy 1] [--regularize 0]
        [--filter-width 1.5] [--lightpath-filter blackman-harris]

Needs Blender as a Python module, numpy and OpenEXR (pip install bpy==5.0.1 OpenEXR numpy,
Python 3.11); not a CI dependency. Steps, each skipped when its output exists:

1. builds OUT_DIR/<scene>.glb for each scene in Blender and exports it with Blender's glTF
   exporter (lights as KHR_lights_punctual);
2. renders each renderer's reference (--ref-spp, seed 1000) of each scene: Cycles imports
   the .glb as a Blender user would (`cycles` below), Lightpath renders the file; then
   renders each reference's glint windows again at --glint-spp (default 262144: the
   pixels round a glint in either reference, where 4096 samples hold a sub-pixel glint's
   few hits) and uses those pixels instead;
3. for each seed and scene, alternately, Cycles and Lightpath at --spp on 2 threads.

Cycles: CPU, 2 threads, its light tree, no denoiser, no adaptive sampling, every bounce
limit at DEPTH, caustics on, Filter Glossy --filter-glossy (default 1, Cycles' own: it
blurs glossy lobes after rough bounces, a regularisation), clamps at --clamp-indirect
(default off; Cycles' factory default is 10). Its time is the second of two renders in
one process (the first loads the kernels). Lightpath: `render --max-depth DEPTH+1` (Mitsuba's count of
segments), `--regularize` (default 0, Lightpath's own; 0.65 matches Filter Glossy 1
after a diffuse bounce), its defaults otherwise (guiding auto), the same clamp; its time
is the whole process's wall time (loading the .glb included).

Both renderers use the same pixel filter: Cycles' default, Blackman-Harris of
--filter-width (default 1.5, Cycles'), which Lightpath has as `--filter blackman-harris`.
`--lightpath-filter box` gives Lightpath its own default instead (the comparison before
Lightpath had the filter: plain MSE then compares the filters at the sun's glints). docs/performance.md,
"Real scenes against Cycles", has the figures.

Prints per scene and seed: wall and CPU seconds, MSE, relMSE (squared error over
reference² + 0.01) and the MSE off the sun's glints (GLINT) against the renderer's own
reference, efficiency = 1 / (MSE × seconds) and Lightpath's efficiency over Cycles' by
each measure; the medians; the two references' means over the
frame and per object (Cycles' Object Index pass masks both, the camera being the same);
and where Lightpath's 64-spp squared error sits (per object, and the share of its 20
worst pixels). Writes OUT_DIR/results_<settings>.json; --reuse reports again from the
images and timings already there. The scene `heldout` is reported apart.

`python real_scenes.py cycles FILE.glb OUT.exr SPP SEED DEPTH CLAMP FILTER_GLOSSY FILTER_WIDTH REPEAT [X0,Y0,X1,Y1]`
is the Cycles step alone (the script runs it in a subprocess, one Blender session per
render; the window is a render border).
"""

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, erode, luminance, rgb  # noqa: E402

WIDTH, HEIGHT = 160, 120
DEPTH = 16  # Cycles' bounces; Lightpath's max-depth is DEPTH + 1 segments
# Pixels brighter than this (luminance) in either reference are the sun's glints in the
# chrome and glass balls: a 0.526° disc of radiance ~2e4 covering a sliver of a pixel,
# which 64 camera samples either miss or hit (Lightpath's glint sampling finds it in
# every sample). How much of the MSE they hold depends on the pixel filter (a 1.5-pixel
# Blackman-Harris spreads a glint over ~9 pixels, a box keeps it in one: hence the same
# filter for both), so the MSE off them (and two pixels round them) is reported too, and
# both references are rendered again there (--glint-spp). The brightest lit surfaces
# here reach ~3.
GLINT = 8.0
HELD_OUT = "heldout"

# Each shot: object placements, the camera and the three lights. shot_a is
# benches/gltf/blender_scene.py's layout; shot_b adds a back wall and moves everything;
# heldout (not looked at while diagnosing) has a corner of two walls, two crates, a
# low sun and the spot aimed at the chrome ball.
SCENES = {
    "shot_a": dict(
        walls=[], crates=[((-1.3, 0.2, 0.5), 0.4, 1.0)], glass=(0.0, -0.4, 0.5, 0.5),
        chrome=(1.1, 0.7, 0.5, 0.5), camera=((0.0, -6.0, 3.0), (65.0, 0.0, 0.0)),
        key=(400.0, (2.5, -1.5, 3.0)), spot=(800.0, (-2.0, -2.0, 4.0), (35.0, 0.0, -45.0)),
        sun=(1.5, (40.0, 20.0, 0.0))),
    "shot_b": dict(
        walls=[((0.0, 2.5, 2.0), (90.0, 0.0, 0.0), (0.7, 0.65, 0.6))],
        crates=[((1.2, 0.6, 0.6), -0.3, 1.2)], glass=(-0.6, -0.8, 0.45, 0.45),
        chrome=(-1.6, 0.8, 0.6, 0.6), camera=((1.5, -5.5, 2.2), (72.0, 0.0, 15.0)),
        key=(300.0, (-1.0, -2.5, 2.5)), spot=(1200.0, (2.5, -2.0, 4.5), (30.0, 0.0, 40.0)),
        sun=(2.0, (55.0, -30.0, 0.0))),
    HELD_OUT: dict(
        walls=[((0.0, 2.0, 2.0), (90.0, 0.0, 0.0), (0.75, 0.7, 0.65)),
               ((-2.5, 0.0, 2.0), (90.0, 0.0, 90.0), (0.5, 0.6, 0.7))],
        crates=[((-1.5, 1.0, 0.5), 0.2, 1.0), ((-1.4, 1.1, 1.35), 0.9, 0.7)],
        glass=(0.4, -0.6, 0.55, 0.55), chrome=(1.3, 0.6, 0.45, 0.45),
        camera=((2.0, -5.0, 2.6), (68.0, 0.0, 25.0)),
        key=(500.0, (1.5, -2.5, 3.5)), spot=(1500.0, (3.0, -1.0, 3.5), (50.0, 0.0, 70.0)),
        sun=(1.2, (75.0, 10.0, -30.0))),
}


def build(out_dir, name, spec):
    """Builds one shot in Blender and exports OUT_DIR/<name>.glb."""
    import bpy
    from benchlib.blender import add_camera, add_light, image_material, principled

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT

    img = bpy.data.images.new(f"{name}_checker", 64, 64, alpha=False)
    px = []
    for y in range(64):
        for x in range(64):
            on = (x // 8 + y // 8) % 2 == 0
            px += [0.9, 0.6, 0.1, 1.0] if on else [0.1, 0.2, 0.8, 1.0]
    img.pixels = px
    img.filepath_raw = os.path.join(out_dir, f"{name}_checker.png")
    img.file_format = "PNG"
    img.save()
    crate_mat = image_material("crate_mat", img, roughness=0.8)

    def named(obj_name, mat):
        obj = bpy.context.object
        obj.name = obj_name
        obj.data.materials.append(mat)
        return obj

    bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
    named("floor", principled("floor_mat", (0.6, 0.6, 0.6), roughness=0.9))
    for i, (loc, rot, colour) in enumerate(spec["walls"]):
        bpy.ops.mesh.primitive_plane_add(size=8, location=loc,
                                         rotation=tuple(math.radians(a) for a in rot))
        named(f"wall{i}", principled(f"wall{i}_mat", colour, roughness=0.9))
    for i, (loc, rot, size) in enumerate(spec["crates"]):
        bpy.ops.mesh.primitive_cube_add(size=size, location=loc, rotation=(0, 0, rot))
        named(f"crate{i}", crate_mat)
    x, y, z, r = spec["glass"]
    bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=(x, y, z), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    named("glass", principled("glass_mat", (1, 1, 1), roughness=0.0, transmission=1.0))
    x, y, z, r = spec["chrome"]
    bpy.ops.mesh.primitive_uv_sphere_add(radius=r, location=(x, y, z), segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    named("chrome", principled("chrome_mat", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.0))

    add_camera(scene, "shot", 40.0, spec["camera"][0],
               tuple(math.radians(a) for a in spec["camera"][1]))

    def light(light_name, kind, energy, location=(0, 0, 5), rotation=(0, 0, 0), color=(1, 1, 1)):
        radians = tuple(math.radians(a) for a in rotation)
        return add_light(scene, light_name, kind, energy, location, radians, color)

    light("key", "POINT", spec["key"][0], spec["key"][1], color=(1.0, 0.9, 0.8))
    spot = light("spot", "SPOT", spec["spot"][0], spec["spot"][1], spec["spot"][2])
    spot.data.spot_size = math.radians(50)
    spot.data.spot_blend = 0.3
    light("sun", "SUN", spec["sun"][0], rotation=spec["sun"][1], color=(0.8, 0.9, 1.0))
    bpy.ops.export_scene.gltf(filepath=os.path.join(out_dir, f"{name}.glb"), export_format="GLB",
                              export_cameras=True, export_lights=True, export_yup=True)


def cycles(glb, out, spp, seed, depth, clamp, filter_glossy, filter_width, repeat, window=None):
    """Renders GLB with Cycles as a Blender user who imports it would; prints the seconds of
    each render (the last is the one to quote: the first loads the kernels). `window`
    (x0, y0, x1, y1 in pixels from the top left, end exclusive): only those pixels (a
    render border), the rest of the frame black."""
    import bpy
    from benchlib.blender import black_world

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(glb))
    sc.camera = [o for o in sc.objects if o.type == "CAMERA"][0]
    for o in sc.objects:
        if o.type == "LIGHT":
            print(f"light {o.name}: {o.data.type} radius {getattr(o.data, 'shadow_soft_size', 0):.3f}")
    black_world(sc)
    c = sc.cycles
    sc.render.engine = "CYCLES"
    c.device = "CPU"
    c.samples = spp
    c.seed = seed
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = clamp
    c.blur_glossy = filter_glossy
    c.pixel_filter_type = "BLACKMAN_HARRIS"
    c.filter_width = filter_width
    c.caustics_reflective = True
    c.caustics_refractive = True
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "transparent_max_bounces"):
        setattr(c, k, depth)
    sc.render.threads_mode = "FIXED"
    sc.render.threads = 2
    sc.render.resolution_x, sc.render.resolution_y = WIDTH, HEIGHT
    sc.render.resolution_percentage = 100
    vl = sc.view_layers[0]
    vl.use_pass_object_index = True
    for i, o in enumerate(sorted([o for o in sc.objects if o.type == "MESH"], key=lambda o: o.name)):
        o.pass_index = i + 1
        print(f"object index {i + 1}: {o.name}")
    imf = sc.render.image_settings
    imf.media_type = "MULTI_LAYER_IMAGE"
    imf.file_format = "OPEN_EXR_MULTILAYER"
    imf.color_depth = "32"
    sc.render.filepath = os.path.abspath(out)
    if window:
        x0, y0, x1, y1 = window
        sc.render.use_border, sc.render.use_crop_to_border = True, False
        sc.render.border_min_x, sc.render.border_max_x = x0 / WIDTH, x1 / WIDTH
        sc.render.border_min_y, sc.render.border_max_y = 1 - y1 / HEIGHT, 1 - y0 / HEIGHT
    for _ in range(repeat):
        t, cpu = time.time(), time.process_time()
        bpy.ops.render.render(write_still=True)
        print(f"CYCLES_SECONDS {time.time() - t:.3f} {time.process_time() - cpu:.3f}")


def run_cycles(glb, out, spp, seed, args, repeat, window=None):
    p = subprocess.run([sys.executable, os.path.abspath(__file__), "cycles", glb, out, str(spp),
                        str(seed), str(DEPTH), str(args.clamp_indirect), str(args.filter_glossy),
                        str(args.filter_width), str(repeat)]
                       + ([",".join(map(str, window))] if window else []),
                       check=True, capture_output=True, text=True)
    secs = [(float(line.split()[1]), float(line.split()[2])) for line in p.stdout.splitlines()
            if line.startswith("CYCLES_SECONDS")]
    objects = {int(line.split()[2].rstrip(":")): line.split()[3] for line in p.stdout.splitlines()
               if line.startswith("object index")}
    return secs[-1], objects


def run_lightpath(glb, out, spp, seed, args, window=None):
    """Renders GLB with Lightpath: (wall seconds, CPU seconds) of the whole process.
    `window`: only those pixels (`--crop`)."""
    t, cpu = time.time(), children_cpu()
    subprocess.run([args.binary, "render", glb, "-o", out, "--quiet", "--aovs", "none", "--threads", "2",
                    "--resolution", f"{WIDTH}x{HEIGHT}", "--spp", str(spp), "--seed", str(seed),
                    "--max-depth", str(DEPTH + 1), "--clamp-indirect", str(args.clamp_indirect),
                    "--regularize", str(args.regularize), "--filter", args.lightpath_filter,
                    "--filter-width", str(args.filter_width)]
                   + (["--crop", ",".join(map(str, window))] if window else []),
                   check=True, capture_output=True)
    return time.time() - t, children_cpu() - cpu


def glint_windows(a, b):
    """Boxes (x0, y0, x1, y1) round the pixels at glints in either reference image, two
    pixels wider than them (where the pixel filter spreads a glint), overlapping ones
    merged."""
    ys, xs = np.nonzero((luminance(a) >= GLINT) | (luminance(b) >= GLINT))
    boxes = [[max(x - 2, 0), max(y - 2, 0), min(x + 3, WIDTH), min(y + 3, HEIGHT)] for y, x in zip(ys, xs)]
    merged = True
    while merged:
        merged = False
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                p, q = boxes[i], boxes[j]
                if p[0] <= q[2] and q[0] <= p[2] and p[1] <= q[3] and q[1] <= p[3]:
                    boxes[i] = [min(p[0], q[0]), min(p[1], q[1]), max(p[2], q[2]), max(p[3], q[3])]
                    del boxes[j]
                    merged = True
                    break
            if merged:
                break
    return [tuple(int(v) for v in b) for b in boxes]


def converge_glints(glb, name, out, tag, renderer, ref, windows, args):
    """The reference `ref` with its glint windows rendered again at --glint-spp (a
    4096-sample reference holds a sub-pixel glint's few hits, so its error, not the
    renderer's, would decide the MSE there). Cached as <ref>_glints<spp>.exr's pixels."""
    done = f"{out}/{name}_{renderer}_{tag}_ref_glints{args.glint_spp}.npy"
    if os.path.exists(done):
        return np.load(done)
    fixed = ref.copy()
    for i, w in enumerate(windows):
        img = f"{out}/{name}_{renderer}_{tag}_glint{i}_{args.glint_spp}.exr"
        if renderer == "cycles":
            run_cycles(glb, img, args.glint_spp, 1001, args, 1, w)
        else:
            run_lightpath(glb, img, args.glint_spp, 1001, args, w)
        x0, y0, x1, y1 = w
        part, _ = beauty(img, renderer)
        # Lightpath writes the window alone (its data window); Cycles the whole frame.
        fixed[y0:y1, x0:x1] = part if part.shape[:2] == (y1 - y0, x1 - x0) else part[y0:y1, x0:x1]
        print(f"{name}: {renderer} reference's glint window {w} at {args.glint_spp} spp", flush=True)
    np.save(done, fixed)
    return fixed


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def beauty(path, renderer):
    ch = channels(path)
    return rgb(ch, "ViewLayer.Combined." if renderer == "cycles" else ""), ch


def object_names(spec):
    """The shot's meshes in Object Index order (cycles() numbers them by name)."""
    names = ["floor", "glass", "chrome"] + [f"wall{i}" for i in range(len(spec["walls"]))]
    return [None] + sorted(names + [f"crate{i}" for i in range(len(spec["crates"]))])


def load_avg():
    return os.getloadavg()[0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out_dir")
    ap.add_argument("binary")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--clamp-indirect", type=float, default=0.0, help="both renderers")
    ap.add_argument("--filter-glossy", type=float, default=1.0, help="Cycles' (its default: 1)")
    ap.add_argument("--regularize", type=float, default=0.0, help="Lightpath's (its default: 0)")
    ap.add_argument("--filter-width", type=float, default=1.5,
                    help="both renderers' Blackman-Harris width (Cycles' default: 1.5)")
    ap.add_argument("--lightpath-filter", choices=["blackman-harris", "box"], default="blackman-harris",
                    help="Lightpath's pixel filter (box: its own default, unlike Cycles')")
    ap.add_argument("--glint-spp", type=int, default=262144,
                    help="each reference's glint windows rendered again at this many samples "
                         "(0: not; the references then hold a glint's few hits)")
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the renders (and their timings in results_*.json) made before")
    ap.add_argument("--refs-only", choices=["cycles", "lightpath"],
                    help="render only this renderer's references, then stop")
    args = ap.parse_args()
    out = os.path.abspath(args.out_dir)
    os.makedirs(out, exist_ok=True)
    names = args.scenes.split(",")
    # Each renderer's images are named by the settings that decide them, so that runs
    # with other settings of the other renderer reuse its references.
    # Images with a renderer's default filter (Cycles' Blackman-Harris 1.5, Lightpath's
    # box) have no filter in their names.
    width = "" if args.filter_width == 1.5 else f"_bh{args.filter_width:g}"
    lp_filter = "" if args.lightpath_filter == "box" else f"_bh{args.filter_width:g}"
    tags = {"cycles": f"c{args.clamp_indirect:g}_fg{args.filter_glossy:g}{width}",
            "lightpath": f"c{args.clamp_indirect:g}_r{args.regularize:g}{lp_filter}"}
    args.tags = tags

    for name in names:
        glb = f"{out}/{name}.glb"
        if not os.path.exists(glb):
            subprocess.run([sys.executable, os.path.abspath(__file__), "build", out, name], check=True,
                           capture_output=True)

    refs, objects, masks = {}, {}, {}
    for name in names:
        glb = f"{out}/{name}.glb"
        cy_ref = f"{out}/{name}_cycles_{tags['cycles']}_ref.exr"
        lp_ref = f"{out}/{name}_lightpath_{tags['lightpath']}_ref.exr"
        if args.refs_only:
            if args.refs_only == "cycles" and not os.path.exists(cy_ref):
                run_cycles(glb, cy_ref, args.ref_spp, 1000, args, 1)
            if args.refs_only == "lightpath" and not os.path.exists(lp_ref):
                run_lightpath(glb, lp_ref, args.ref_spp, 1000, args)
            continue
        if not os.path.exists(cy_ref):
            (s, _), _ = run_cycles(glb, cy_ref, args.ref_spp, 1000, args, 1)
            print(f"{name}: Cycles reference {args.ref_spp} spp in {s:.0f} s", flush=True)
        if not os.path.exists(lp_ref):
            s, _ = run_lightpath(glb, lp_ref, args.ref_spp, 1000, args)
            print(f"{name}: Lightpath reference {args.ref_spp} spp in {s:.0f} s", flush=True)
        cy, cy_ch = beauty(cy_ref, "cycles")
        lp, _ = beauty(lp_ref, "lightpath")
        if args.glint_spp:
            windows = glint_windows(cy, lp)
            cy = converge_glints(glb, name, out, tags["cycles"], "cycles", cy, windows, args)
            lp = converge_glints(glb, name, out, tags["lightpath"], "lightpath", lp, windows, args)
        refs[name] = {"cycles": cy, "lightpath": lp}
        objects[name] = np.rint(cy_ch["ViewLayer.Object Index.X"]).astype(int)
        # Off the glints and two pixels round them (where Cycles' filter spreads them).
        masks[name] = erode((luminance(cy) < GLINT) & (luminance(lp) < GLINT), 2)

    if args.refs_only:
        return
    results = f"{out}/results_{tags['cycles']}_{tags['lightpath']}.json"
    before = {}
    if args.reuse and os.path.exists(results):
        with open(results) as f:
            before = {(r["scene"], r["seed"], r["renderer"]): r for r in json.load(f)["runs"]}
    runs = []
    for seed in range(1, args.seeds + 1):
        for name in names:
            glb = f"{out}/{name}.glb"
            # Alternate which renderer goes first, so a change in load hits both.
            order = ["cycles", "lightpath"] if seed % 2 else ["lightpath", "cycles"]
            for renderer in order:
                img = f"{out}/{name}_{renderer}_{tags[renderer]}_{args.spp}_{seed}.exr"
                load = load_avg()
                if (name, seed, renderer) in before and os.path.exists(img):
                    r = before[(name, seed, renderer)]
                    secs, cpu, load = r["seconds"], r["cpu"], r["load"]
                elif renderer == "cycles":
                    (secs, cpu), _ = run_cycles(glb, img, args.spp, seed, args, 2)
                else:
                    secs, cpu = run_lightpath(glb, img, args.spp, seed, args)
                x, _ = beauty(img, renderer)
                ref = refs[name][renderer]
                err = (x - ref) ** 2
                mse = float(err.mean())
                rel = float((err / (ref ** 2 + 0.01)).mean())
                off = float(err[masks[name]].mean())
                lum = luminance(err).ravel()
                top = float(np.sort(lum)[-20:].sum() / max(lum.sum(), 1e-30))
                runs.append(dict(scene=name, seed=seed, renderer=renderer, seconds=secs, cpu=cpu, mse=mse,
                                 relmse=rel, mse_off_glints=off, efficiency=1.0 / (mse * secs),
                                 top20_share=top,
                                 load=load, mean=float(x.mean())))
                print(f"{name} seed {seed} {renderer:>9}: {secs:6.2f} s ({cpu:5.2f} CPU-s)  MSE {mse:.3e}  relMSE {rel:.3e}  off glints {off:.3e}  "
                      f"eff {1.0 / (mse * secs):9.1f}  worst-20-px share {top:.2f}  load {load:.1f}",
                      flush=True)

    report(runs, refs, objects, masks, names, out, args)


def report(runs, refs, objects, masks, names, out, args):
    summary = {}
    print(f"\n{args.spp} spp, {WIDTH}x{HEIGHT}, depth {DEPTH}, clamp-indirect {args.clamp_indirect:g}, "
          f"Cycles filter glossy {args.filter_glossy:g}, Lightpath regularize {args.regularize:g}, "
          f"pixel filters Cycles blackman-harris {args.filter_width:g}, Lightpath "
          f"{args.lightpath_filter}, references {args.ref_spp} spp")
    for group in ([n for n in names if n != HELD_OUT], [n for n in names if n == HELD_OUT]):
        for name in group:
            rs = [r for r in runs if r["scene"] == name]
            line = {}
            for seed in sorted({r["seed"] for r in rs}):
                by = {r["renderer"]: r for r in rs if r["seed"] == seed}
                if len(by) == 2:
                    lp_, cy_ = by["lightpath"], by["cycles"]
                    print(f"  {name} seed {seed}: Lightpath {lp_['seconds']:.2f} s ({lp_['cpu']:.2f} CPU-s) "
                          f"MSE {lp_['mse']:.3e} | Cycles {cy_['seconds']:.2f} s ({cy_['cpu']:.2f} CPU-s) "
                          f"MSE {cy_['mse']:.3e} | efficiency ratio "
                          f"{cy_['mse'] * cy_['seconds'] / (lp_['mse'] * lp_['seconds']):.2f}x wall, "
                          f"{cy_['mse'] * cy_['cpu'] / (lp_['mse'] * lp_['cpu']):.2f}x CPU, "
                          f"{cy_['relmse'] * cy_['seconds'] / (lp_['relmse'] * lp_['seconds']):.2f}x relMSE, "
                          f"{cy_['mse_off_glints'] * cy_['seconds'] / (lp_['mse_off_glints'] * lp_['seconds']):.2f}x "
                          f"MSE off glints")
            for renderer in ("lightpath", "cycles"):
                mine = [r for r in rs if r["renderer"] == renderer]
                if mine:
                    secs = statistics.median(r["seconds"] for r in mine)
                    cpu = statistics.median(r["cpu"] for r in mine)
                    mse = statistics.median(r["mse"] for r in mine)
                    rel = statistics.median(r["relmse"] for r in mine)
                    off = statistics.median(r["mse_off_glints"] for r in mine)
                    line[renderer] = dict(seconds=secs, cpu=cpu, mse=mse, relmse=rel, mse_off_glints=off,
                                          efficiency=1 / (mse * secs))
            if len(line) == 2:
                ratio = line["lightpath"]["efficiency"] / line["cycles"]["efficiency"]
                line["ratio"] = ratio
                line["ratio_cpu"] = (line["cycles"]["mse"] * line["cycles"]["cpu"]
                                     / (line["lightpath"]["mse"] * line["lightpath"]["cpu"]))
                print(f"  {name}{' (held out)' if name == HELD_OUT else ''} medians: Lightpath "
                      f"{line['lightpath']['seconds']:.2f} s MSE {line['lightpath']['mse']:.3e}, Cycles "
                      f"{line['cycles']['seconds']:.2f} s MSE {line['cycles']['mse']:.3e}: "
                      f"ratio {ratio:.2f}x wall, {line['ratio_cpu']:.2f}x CPU")
                for metric in ("relmse", "mse_off_glints"):
                    line[f"ratio_{metric}"] = (line["cycles"][metric] * line["cycles"]["seconds"]
                                               / (line["lightpath"][metric] * line["lightpath"]["seconds"]))
                print(f"    relMSE Lightpath {line['lightpath']['relmse']:.3e}, Cycles "
                      f"{line['cycles']['relmse']:.3e}: ratio {line['ratio_relmse']:.2f}x; off the "
                      f"{int((~masks[name]).sum())} pixels at glints MSE Lightpath "
                      f"{line['lightpath']['mse_off_glints']:.3e}, Cycles {line['cycles']['mse_off_glints']:.3e}: "
                      f"ratio {line['ratio_mse_off_glints']:.2f}x")
            # The two references: whole frame and per object.
            cy, lp = refs[name]["cycles"], refs[name]["lightpath"]
            ids = objects[name]
            label = object_names(SCENES[name])
            per = {"frame": float(lp.mean() / cy.mean())}
            for i in sorted(set(ids.ravel()) - {0}):
                m = ids == i
                per[label[i]] = float(lp[m].mean() / max(cy[m].mean(), 1e-12))
            line["ref_mean_ratio"] = per
            print(f"  {name} references, Lightpath mean / Cycles mean: "
                  + ", ".join(f"{k} {v:.4f}" for k, v in per.items()))
            # Where Lightpath's error sits: each object's share of the squared error (seed 1).
            for renderer in ("lightpath", "cycles"):
                path = f"{out}/{name}_{renderer}_{args.tags[renderer]}_{args.spp}_1.exr"
                if os.path.exists(path):
                    x, _ = beauty(path, renderer)
                    err = ((x - refs[name][renderer]) ** 2).sum(axis=-1)
                    shares = {label[i] or "background": float(err[ids == i].sum() / err.sum())
                              for i in sorted(set(ids.ravel()))}
                    line[f"{renderer}_error_share_seed1"] = shares
                    print(f"  {name} {renderer} seed 1 error share by object index: "
                          + ", ".join(f"{k} {v:.2f}" for k, v in shares.items()))
            summary[name] = line
    with open(f"{out}/results_{args.tags['cycles']}_{args.tags['lightpath']}.json", "w") as f:
        json.dump(dict(runs=runs, summary=summary), f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "build":
        build(sys.argv[2], sys.argv[3], SCENES[sys.argv[3]])
    elif len(sys.argv) > 1 and sys.argv[1] == "cycles":
        glb, out, spp, seed, depth, clamp, filter_glossy, filter_width, repeat = sys.argv[2:11]
        window = tuple(int(v) for v in sys.argv[11].split(",")) if len(sys.argv) > 11 else None
        cycles(glb, out, int(spp), int(seed), int(depth), float(clamp), float(filter_glossy),
               float(filter_width), int(repeat), window)
    else:
        main()
