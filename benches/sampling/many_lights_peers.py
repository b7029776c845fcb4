"""The many-light set (issue 29) with peers side by side: Lightpath, Mitsuba 3 and Cycles
(path guiding off and on), each on the same scenes and each against its own reference.

    /work/venv311/bin/python benches/sampling/many_lights_peers.py LIGHTPATH OUT_DIR \
        [--spp 16] [--seeds 2] [--recipes sky_key_lamps,corridor] [--ref-spp 4096] [--repeat 5]

Needs, in the Python that runs it, bpy 5.0.1 (Blender as a module), numpy and OpenEXR;
Mitsuba 3 runs in a subprocess under $MITSUBA_PYTHON (default `python3`, which must
import mitsuba and numpy). Everything renders at 128 x 128, 2 threads, one render at a time.

The scenes are many_lights_recipes.py's (the same seeded placements as
many_lights_set.py), emitted as a Lightpath TOML, a Mitsuba dict and a bpy scene:

  Lightpath  the TOML as many_lights_set.py renders it, `--light-selection tree` (default),
             clamps off, box filter; wall seconds of the whole process.
  Mitsuba    `llvm_ad_rgb`, `path` (max_depth and rr_depth as the TOML), independent
             sampler (its default), box filter; lamps and panels as sphere / rectangle
             shapes with an area emitter and a `null` BSDF (the camera sees through them,
             as through Lightpath's `camera_visible = false` lights), `hide_emitters` for
             those, and the dome added back where camera rays miss (alpha). Uniform emitter
             selection (Mitsuba's only one). Wall seconds of `mi.render` after a warm-up
             render of the same size (the JIT kernel compiled and cached).
  Cycles     CPU, light tree on, clamps off, Filter Glossy 0, box filter 1 px,
             max_bounces = max_depth - 2, other settings Cycles' defaults (light threshold
             0.01); sphere lamps as point lights of that radius (soft falloff off), rects as
             area lights, spots, sun (angle 0), world colour = dome; lights hidden from the
             camera as in the TOML. Guiding off, and on (use_guiding + use_surface_guiding,
             the other guiding settings Cycles' defaults: 128 training samples). Wall
             seconds of the render operator after warm-up renders of both kinds in the
             same session; one reference (guiding off) for both.

Units (Lightpath -> Mitsuba / Cycles): point and spot intensity I W/sr -> I / 4*pi*I W;
sphere radiance L, radius r -> area emitter L / point light of 4*pi^2*r^2*L W; rect
radiance L of area A -> L / area light of pi*A*L W; distant irradiance E -> E / sun
strength E; dome radiance -> constant / world colour. Spot: cone_angle (full) and
cone_softness -> Mitsuba cutoff = cone/2, beam width = cone/2 - softness (linear in angle)
/ Cycles spot size = cone, blend = (cos inner - cos outer) / (1 - cos outer) (smoothstep in
the cosine, as Lightpath). Conductor f0, roughness r -> roughconductor (`none`, reflectance
f0, alpha r^2) / Principled metallic (base colour f0, roughness r).

With --repeat R each timed render is run R times (the same image) and its fastest time is
kept: on a shared machine the minimum is the least disturbed. References that exist in
OUT_DIR are reused, so a re-run with another --spp, --seeds or --repeat renders only those.

Prints per scene each renderer's median wall seconds (and CPU seconds: Lightpath's whole
process, the peers' process time over the render call), MSE against its own reference, and
efficiency 1 / (MSE x s), Lightpath's efficiency over each peer's, and each reference's mean
over Lightpath's; writes OUT_DIR/results.json.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from many_lights_recipes import build, matrix, to_toml  # noqa: E402

SIZE = 128
PEER_RECIPES = ["sky_key_lamps", "corridor", "clusters", "ceiling_grid", "spots", "two_big_many"]


def quad_mesh(corners):
    return [tuple(c) for c in corners], [(0, 1, 2), (0, 2, 3)]


def cube_mesh():
    v = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    # Outward faces, counter-clockwise seen from outside.
    q = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return v, [t for a, b, c, d in q for t in ((a, b, c), (a, c, d))]


# ---------------------------------------------------------------- Mitsuba (subprocess)

def write_ply(path, verts, faces):
    """Binary little-endian PLY with positions only (flat shading, winding kept)."""
    import numpy as np
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar uint vertex_indices\nend_header\n")
    rec = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<u4", (3,))])
    rec["n"] = 3
    rec["i"] = faces
    with open(path, "wb") as f:
        f.write(header.encode("ascii") + verts.tobytes() + rec.tobytes())


def mitsuba_main(desc_path, out_prefix, ref_spp, spp, seeds, repeat=1):
    for cand in ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"):
        if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(cand):
            os.environ["DRJIT_LIBLLVM_PATH"] = cand
    import numpy as np
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(2)
    with open(desc_path) as f:
        desc = json.load(f)
    T = mi.ScalarTransform4f

    def rgb(v):
        return {"type": "rgb", "value": [float(x) for x in v]}

    def to_world(m):
        return T(mi.ScalarMatrix4f(np.array(m, dtype=np.float64)))

    cam = desc["camera"]
    d = {"type": "scene",
         "integrator": {"type": "path", "max_depth": desc["max_depth"], "rr_depth": desc["rr_depth"],
                        "hide_emitters": True},
         "sensor": {"type": "perspective", "fov": cam["fov"], "fov_axis": "smaller",
                    "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=[0, 1, 0]),
                    "sampler": {"type": "independent", "sample_count": spp},
                    "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "pixel_format": "rgba",
                             "component_format": "float32", "rfilter": {"type": "box"}}}}
    bsdfs = {}
    for name, m in desc["materials"].items():
        if m["type"] == "diffuse":
            bsdfs[name] = {"type": "diffuse", "reflectance": rgb(m["albedo"])}
        else:
            bsdfs[name] = {"type": "roughconductor", "material": "none", "distribution": "ggx",
                           "alpha": m["roughness"] ** 2, "specular_reflectance": rgb(m["f0"])}
    for i, o in enumerate(desc["objects"]):
        bsdf = bsdfs[o["material"]]
        if o["shape"] == "quad":
            v, f = quad_mesh(o["corners"])
            ply = f"{out_prefix}_{o['name']}.ply"
            write_ply(ply, np.array(v, dtype="<f4"), np.array(f, dtype="<u4"))
            d[f"shape{i}"] = {"type": "ply", "filename": ply, "face_normals": True, "bsdf": bsdf}
        elif o["shape"] == "cube":
            d[f"shape{i}"] = {"type": "cube", "to_world": to_world(matrix(o["scale"], o["rotate"], o["translate"])),
                              "bsdf": bsdf}
        else:
            d[f"shape{i}"] = {"type": "sphere", "center": o["center"], "radius": o["radius"], "bsdf": bsdf}
    dome = None
    for i, light in enumerate(desc["lights"]):
        k = light["type"]
        if k == "sphere":
            d[f"light{i}"] = {"type": "sphere", "center": light["center"], "radius": light["radius"],
                              "bsdf": {"type": "null"}, "emitter": {"type": "area", "radiance": rgb(light["radiance"])}}
        elif k == "rect":
            d[f"light{i}"] = {"type": "rectangle",
                              "to_world": to_world(matrix(light["scale"], light["rotate"], light["translate"])),
                              "bsdf": {"type": "null"}, "emitter": {"type": "area", "radiance": rgb(light["radiance"])}}
        elif k == "point":
            d[f"light{i}"] = {"type": "point", "position": light["position"], "intensity": rgb(light["intensity"])}
        elif k == "spot":
            p, di = np.array(light["position"], float), np.array(light["direction"], float)
            up = [1, 0, 0] if abs(di[0]) < 0.9 * np.linalg.norm(di) else [0, 1, 0]
            half = light["cone_angle"] / 2
            d[f"light{i}"] = {"type": "spot", "to_world": T().look_at(origin=p.tolist(), target=(p + di).tolist(), up=up),
                              "intensity": rgb(light["intensity"]), "cutoff_angle": half,
                              "beam_width": max(half - light["cone_softness"], 0.0)}
        elif k == "distant":
            d[f"light{i}"] = {"type": "directional", "direction": light["direction"],
                              "irradiance": rgb(light["irradiance"])}
        elif k == "dome":
            dome = np.array(light["radiance"], float)
            d[f"light{i}"] = {"type": "constant", "radiance": rgb(dome)}
        else:
            raise ValueError(k)
    scene = mi.load_dict(d)

    def render(n, seed, pass_spp=256):
        acc = None
        passes = max(n // pass_spp, 1)
        for j in range(passes):
            img = np.array(mi.render(scene, spp=min(n, pass_spp), seed=seed + j), dtype=np.float64)
            acc = img if acc is None else acc + img
        img = acc / passes
        out = img[..., :3]
        if dome is not None:  # hidden emitters hide the dome too: add it back where rays missed
            out = out + (1.0 - img[..., 3:4]) * dome
        return out

    def save(img, path):
        mi.Bitmap(img.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)

    res = {}
    ref = f"{out_prefix}_ref.exr"
    if not os.path.exists(ref):
        t = time.time()
        save(render(ref_spp, 10_000_000), ref)
        res["ref_seconds"] = time.time() - t
    render(spp, 0)  # warm-up: compiles (or loads) the kernel of this size
    for seed in range(1, seeds + 1):
        load, times, cpus = os.getloadavg()[0], [], []
        for _ in range(repeat):
            t, cpu = time.time(), time.process_time()
            img = render(spp, seed * 1000)
            times.append(time.time() - t)
            cpus.append(time.process_time() - cpu)
        res[f"seed{seed}"] = {"seconds": min(times), "cpu": min(cpus), "times": times, "load": load}
        save(img, f"{out_prefix}_{spp}_{seed}.exr")
    print("RESULT " + json.dumps(res), flush=True)


# ---------------------------------------------------------------- Cycles (subprocess)

def look_at_matrix(pos, target, up=(0, 1, 0)):
    from mathutils import Matrix, Vector
    p, t, u = Vector(pos), Vector(target), Vector(up)
    f = (t - p).normalized()
    if abs(f.dot(u.normalized())) > 0.99:
        u = Vector((1, 0, 0))
    r = f.cross(u).normalized()
    uu = r.cross(f)
    m = Matrix.Identity(4)  # local -Z along f, +Y up (cameras, spots, suns)
    for i in range(3):
        m[i][0], m[i][1], m[i][2], m[i][3] = r[i], uu[i], -f[i], p[i]
    return m


def cycles_main(desc_path, out_prefix, ref_spp, spp, seeds, repeat=1):
    import bpy
    from mathutils import Matrix
    with open(desc_path) as f:
        desc = json.load(f)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    c = sc.cycles
    c.device = "CPU"
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.use_light_tree = True
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    bounces = desc["max_depth"] - 2
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces", "transparent_max_bounces"):
        setattr(c, k, bounces)
    c.volume_bounces = 0
    r = sc.render
    r.threads_mode = "FIXED"
    r.threads = 2
    r.resolution_x = r.resolution_y = SIZE
    r.resolution_percentage = 100
    r.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    imf = r.image_settings
    imf.media_type = "IMAGE"
    imf.file_format = "OPEN_EXR"
    imf.color_mode = "RGB"
    imf.color_depth = "32"
    r.use_file_extension = False

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0, 0, 0, 1)
    bg.inputs["Strength"].default_value = 1.0
    sc.world = world

    cam = desc["camera"]
    cd = bpy.data.cameras.new("camera")
    cd.lens_unit = "FOV"
    cd.sensor_fit = "HORIZONTAL"  # square film: the smaller axis is either
    cd.angle = math.radians(cam["fov"])
    co = bpy.data.objects.new("camera", cd)
    sc.collection.objects.link(co)
    co.matrix_world = look_at_matrix(cam["position"], cam["look_at"])
    sc.camera = co

    mats = {}
    for name, m in desc["materials"].items():
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        nt = mat.node_tree
        nt.nodes.clear()
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        if m["type"] == "diffuse":
            b = nt.nodes.new("ShaderNodeBsdfDiffuse")
            b.inputs["Color"].default_value = (*m["albedo"], 1)
            b.inputs["Roughness"].default_value = 0.0
        else:
            b = nt.nodes.new("ShaderNodeBsdfPrincipled")
            b.inputs["Base Color"].default_value = (*m["f0"], 1)
            b.inputs["Metallic"].default_value = 1.0
            b.inputs["Roughness"].default_value = m["roughness"]
        nt.links.new(b.outputs[0], out.inputs["Surface"])
        mats[name] = mat

    def mesh_object(name, verts, faces, mat, m=None, smooth=False):
        me = bpy.data.meshes.new(name)
        me.from_pydata(verts, [], faces)
        me.update()
        for poly in me.polygons:
            poly.use_smooth = smooth
        me.materials.append(mat)
        ob = bpy.data.objects.new(name, me)
        sc.collection.objects.link(ob)
        if m is not None:
            ob.matrix_world = Matrix(m)
        return ob

    for o in desc["objects"]:
        if o["shape"] == "quad":
            mesh_object(o["name"], *quad_mesh(o["corners"]), mats[o["material"]])
        elif o["shape"] == "cube":
            mesh_object(o["name"], *cube_mesh(), mats[o["material"]], matrix(o["scale"], o["rotate"], o["translate"]))
        else:
            bpy.ops.mesh.primitive_uv_sphere_add(radius=o["radius"], location=o["center"], segments=64, ring_count=32)
            ob = bpy.context.object
            ob.name = o["name"]
            bpy.ops.object.shade_smooth()
            ob.data.materials.append(mats[o["material"]])

    def add_light(i, kind, colour, watts_per_unit, m):
        mx = max(colour)
        data = bpy.data.lights.new(f"light{i}", kind)
        data.color = [x / mx for x in colour] if mx > 0 else (1, 1, 1)
        data.energy = mx * watts_per_unit
        ob = bpy.data.objects.new(f"light{i}", data)
        sc.collection.objects.link(ob)
        ob.matrix_world = m
        return ob, data

    for i, light in enumerate(desc["lights"]):
        k = light["type"]
        if k == "sphere":
            rad = light["radius"]
            ob, data = add_light(i, "POINT", light["radiance"], 4 * math.pi ** 2 * rad ** 2,
                                 Matrix.Translation(light["center"]))
            data.shadow_soft_size = rad
            data.use_soft_falloff = False
        elif k == "point":
            ob, data = add_light(i, "POINT", light["intensity"], 4 * math.pi, Matrix.Translation(light["position"]))
            data.shadow_soft_size = 0.0
            data.use_soft_falloff = False
        elif k == "spot":
            p, di = light["position"], light["direction"]
            ob, data = add_light(i, "SPOT", light["intensity"], 4 * math.pi,
                                 look_at_matrix(p, [p[j] + di[j] for j in range(3)]))
            data.shadow_soft_size = 0.0
            data.use_soft_falloff = False
            half = math.radians(light["cone_angle"] / 2)
            inner = max(half - math.radians(light["cone_softness"]), 0.0)
            data.spot_size = 2 * half
            data.spot_blend = (math.cos(inner) - math.cos(half)) / (1 - math.cos(half))
        elif k == "rect":
            sx, sy = light["scale"][0], light["scale"][1]
            area = 4 * sx * sy
            # Lightpath's rect emits along its +z, Blender's area light along its -Z:
            # the placement without its scale, then a half turn about X.
            m = Matrix(matrix((1, 1, 1), light["rotate"], light["translate"])) @ Matrix.Rotation(math.pi, 4, "X")
            ob, data = add_light(i, "AREA", light["radiance"], math.pi * area, m)
            data.shape = "RECTANGLE"
            data.size, data.size_y = 2 * sx, 2 * sy
        elif k == "distant":
            di = light["direction"]
            ob, data = add_light(i, "SUN", light["irradiance"], 1.0, look_at_matrix((0, 0, 0), di))
            data.angle = 0.0
        elif k == "dome":
            bg.inputs["Color"].default_value = (*light["radiance"], 1)
            continue
        else:
            raise ValueError(k)
        if not light.get("camera_visible", True):
            ob.visible_camera = False

    def render(path, n, seed, guiding):
        c.samples = n
        c.seed = seed
        c.use_guiding = guiding
        c.use_surface_guiding = guiding
        r.filepath = path
        t, cpu = time.time(), time.process_time()
        bpy.ops.render.render(write_still=True)
        return time.time() - t, time.process_time() - cpu

    res = {}
    ref = f"{out_prefix}_ref.exr"
    if not os.path.exists(ref):
        res["ref_seconds"] = render(ref, ref_spp, 10_000_000, False)[0]
    tmp = f"{out_prefix}_warmup.exr"
    render(tmp, spp, 0, False)
    render(tmp, spp, 0, True)
    for seed in range(1, seeds + 1):
        for guiding in (False, True):
            load = os.getloadavg()[0]
            tag = "guided" if guiding else "plain"
            runs = [render(f"{out_prefix}_{tag}_{spp}_{seed}.exr", spp, seed, guiding) for _ in range(repeat)]
            times = [t for t, _ in runs]
            res[f"{tag}{seed}"] = {"seconds": min(times), "cpu": min(c for _, c in runs), "times": times,
                                   "load": load}
    print("RESULT " + json.dumps(res), flush=True)


# ---------------------------------------------------------------- driver

def result_line(stdout):
    return json.loads([ln for ln in stdout.splitlines() if ln.startswith("RESULT ")][-1][7:])


def lightpath(binary, scene, img, spp, seed, repeat=1):
    args = [binary, "render", scene, "-o", img, "--aovs", "none", "--resolution", f"{SIZE}x{SIZE}",
            "--spp", str(spp), "--seed", str(seed), "--light-selection", "tree", "--clamp-indirect", "0",
            "--threads", "2", "--quiet"]
    load, times, cpus = os.getloadavg()[0], [], []
    for _ in range(repeat):
        t, cpu = time.time(), children_cpu()
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
        times.append(time.time() - t)
        cpus.append(children_cpu() - cpu)
    return {"seconds": min(times), "cpu": min(cpus), "times": times, "load": load}


def children_cpu():
    import resource
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main():
    if len(sys.argv) > 1 and sys.argv[1] in ("mitsuba", "cycles"):
        fn = mitsuba_main if sys.argv[1] == "mitsuba" else cycles_main
        fn(sys.argv[2], sys.argv[3], *(int(a) for a in sys.argv[4:8]))
        return
    sys.path.insert(0, os.path.join(HERE, ".."))
    from benchlib.exr import channels, rgb

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binary")
    ap.add_argument("out_dir")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--recipes", default=",".join(PEER_RECIPES))
    ap.add_argument("--ref-spp", default="4096",
                    help="reference spp: one number, or lightpath=N,mitsuba=N,cycles=N")
    ap.add_argument("--renderers", default="lightpath,mitsuba,cycles")
    ap.add_argument("--repeat", type=int, default=1,
                    help="time each 16-spp render this many times and keep the fastest (a loaded machine)")
    args = ap.parse_args()
    out = os.path.abspath(args.out_dir)
    os.makedirs(out, exist_ok=True)
    ref_spp = {k: int(args.ref_spp) for k in ("lightpath", "mitsuba", "cycles")} if "=" not in args.ref_spp \
        else {k: int(v) for k, v in (p.split("=") for p in args.ref_spp.split(","))}
    renderers = args.renderers.split(",")
    mpy = os.environ.get("MITSUBA_PYTHON", "python3")
    results_path = os.path.join(out, "results.json")
    results = json.load(open(results_path)) if os.path.exists(results_path) else {}

    for name in args.recipes.split(","):
        desc = build(name)
        base = os.path.join(out, name)
        with open(base + ".toml", "w") as f:
            f.write(to_toml(desc))
        with open(base + ".json", "w") as f:
            json.dump(desc, f)
        runs = results.setdefault(name, {})
        if "lightpath" in renderers:
            ref = f"{base}_lightpath_ref.exr"
            if not os.path.exists(ref):
                runs["lightpath_ref"] = lightpath(args.binary, base + ".toml", ref, ref_spp["lightpath"], 99)
            for seed in range(1, args.seeds + 1):
                runs[f"lightpath{seed}"] = lightpath(args.binary, base + ".toml",
                                                     f"{base}_lightpath_{args.spp}_{seed}.exr", args.spp, seed,
                                                     args.repeat)
        if "mitsuba" in renderers:
            p = subprocess.run([mpy, os.path.abspath(__file__), "mitsuba", base + ".json", base + "_mitsuba",
                                str(ref_spp["mitsuba"]), str(args.spp), str(args.seeds), str(args.repeat)],
                               check=True, capture_output=True, text=True)
            for k, v in result_line(p.stdout).items():
                runs["mitsuba_ref" if k == "ref_seconds" else f"mitsuba{k[4:]}"] = \
                    {"seconds": v} if k == "ref_seconds" else v
        if "cycles" in renderers:
            p = subprocess.run([sys.executable, os.path.abspath(__file__), "cycles", base + ".json", base + "_cycles",
                                str(ref_spp["cycles"]), str(args.spp), str(args.seeds), str(args.repeat)],
                               check=True, capture_output=True, text=True)
            for k, v in result_line(p.stdout).items():
                if k == "ref_seconds":
                    runs["cycles_ref"] = {"seconds": v}
                else:
                    runs[("cycles_guided" if k.startswith("guided") else "cycles_plain") + k[-1]] = v
        with open(results_path, "w") as f:
            json.dump(results, f, indent=1)

        def img(path):
            ch = channels(path)
            return rgb(ch)

        refs = {"lightpath": f"{base}_lightpath_ref.exr", "mitsuba": f"{base}_mitsuba_ref.exr",
                "cycles_plain": f"{base}_cycles_ref.exr", "cycles_guided": f"{base}_cycles_ref.exr"}
        files = {"lightpath": f"{base}_lightpath_{args.spp}_{{}}.exr", "mitsuba": f"{base}_mitsuba_{args.spp}_{{}}.exr",
                 "cycles_plain": f"{base}_cycles_plain_{args.spp}_{{}}.exr",
                 "cycles_guided": f"{base}_cycles_guided_{args.spp}_{{}}.exr"}
        summary = {}
        for who, ref in refs.items():
            if not os.path.exists(ref) or f"{who}1" not in runs:
                continue
            r = img(ref)
            mses, secs, cpus, loads, means = [], [], [], [], []
            for seed in range(1, args.seeds + 1):
                x = img(files[who].format(seed))
                mses.append(float(((x - r) ** 2).mean()))
                means.append(float(x.mean()))
                secs.append(runs[f"{who}{seed}"]["seconds"])
                cpus.append(runs[f"{who}{seed}"].get("cpu", float("nan")))
                loads.append(runs[f"{who}{seed}"]["load"])
            mse, s = statistics.median(mses), statistics.median(secs)
            c = statistics.median(cpus)
            summary[who] = dict(mse=mse, seconds=s, eff=1 / (mse * s), cpu=c, eff_cpu=1 / (mse * c),
                                ref_mean=float(r.mean()),
                                mean16=statistics.mean(means), load=max(loads),
                                ref_seconds=runs.get(who.split("_")[0] + "_ref", {}).get("seconds"))
        runs["summary"] = summary
        with open(results_path, "w") as f:
            json.dump(results, f, indent=1)
        lp = summary.get("lightpath")
        for who, v in summary.items():
            extra = ""
            if lp and who != "lightpath":
                extra = (f"  LP eff / this {lp['eff'] / v['eff']:6.2f}x (CPU {lp['eff_cpu'] / v['eff_cpu']:6.2f}x)"
                         f"  ref mean / LP's {v['ref_mean'] / lp['ref_mean']:.3f}")
            print(f"{name:14s} {who:13s} {v['seconds']:6.3f} s ({v['cpu']:6.3f} CPU s)  MSE {v['mse']:.3e}  "
                  f"eff {v['eff']:10.4g}  ref mean {v['ref_mean']:.4f} (16-spp mean {v['mean16']:.4f})  load {v['load']:.2f}{extra}",
                  flush=True)


if __name__ == "__main__":
    main()
