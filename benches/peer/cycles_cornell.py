#!/usr/bin/env python3
"""Blender Cycles (CPU) peer renderer for the Cornell box in cornell_scene.json.

Runs with the pip-installed `bpy` module (Blender as a Python module, no blender binary):
    python3 cycles_cornell.py --spp 64 --max-depth 8 --threads 2
It also works inside a blender binary:
    blender -b --factory-startup --python cycles_cornell.py -- --spp 64

The scene is rebuilt from cornell_scene.json (world-space triangles, diffuse albedos,
one-sided area emitter, box pixel filter, black background). Depth convention:
--max-depth is Mitsuba's (path segments; 2 = direct lighting only) and is mapped to
Cycles' max_bounces = max_depth - 2 (Cycles 0 bounces = direct lighting only).

Outputs PREFIX.exr, a multilayer float32 EXR with the passes
  Combined, DiffDir, DiffInd, DiffCol, GlossDir, GlossInd, GlossCol, Emit,
  Combined_<lightgroup> (one light group per emitter object)
and PREFIX.png (combined, sRGB 'Standard' view transform).
--guiding 1 turns on Cycles path guiding (Open PGL) on surfaces (see --help).
Note: Cycles' Diff{Dir,Ind} passes are irradiance-like: the diffuse contribution to
Combined is (DiffDir + DiffInd) * DiffCol.
"""
import argparse
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))  # copied from shared/peers (+ a single-layer EXR with --beauty-only); reads cornell_scene.json beside it


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", default=os.path.join(HERE, "cornell_scene.json"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-depth", type=int, default=8, help="Mitsuba convention; Cycles max_bounces = max_depth - 2")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--res", type=int, nargs=2, default=None, metavar=("W", "H"))
    ap.add_argument("--filter", default=None, help="override pixel filter: box (default from JSON) or gaussian/blackman_harris")
    ap.add_argument("--light-tree", type=int, default=1, help="Cycles light tree on/off (1/0)")
    ap.add_argument("--two-sided", action="store_true", help="do NOT force one-sided BSDFs/emission (Cycles default behaviour)")
    ap.add_argument("--out", default=None, help="output prefix (default out/cycles_<spp>spp_d<depth>)")
    ap.add_argument("--save-blend", default=None, help="also save the built scene as a .blend file")
    ap.add_argument("--adaptive-threshold", type=float, default=0.0,
                    help="Cycles adaptive sampling's noise threshold (0: off, the default); --spp is then the most")
    ap.add_argument("--adaptive-min-samples", type=int, default=0,
                    help="with --adaptive-threshold: samples every pixel takes first (0: Cycles' automatic choice)")
    ap.add_argument("--repeat", type=int, default=1, help="render this many times (timing); the last one is written")
    ap.add_argument("--beauty-only", action="store_true",
                    help="no extra passes and no light groups (Combined only), for beauty-only timing")
    ap.add_argument("--guiding", type=int, default=0, choices=(0, 1),
                    help="Cycles path guiding (Open PGL) on surfaces (1) or off (0, the default); volume guiding stays off. "
                         "Cycles trains during the render and keeps the training samples in the image")
    ap.add_argument("--guiding-training-samples", type=int, default=None,
                    help="with --guiding 1: Cycles' guiding_training_samples (its default 128; 0 trains to the last sample). "
                         "Cycles counts it in guiding-field updates (PathTrace::guiding_prepare_structures compares it with "
                         "the field's iteration), and while training it renders at most 4 samples per update: 128 trains "
                         "for up to 512 spp")
    ap.add_argument("--guiding-deterministic", type=int, default=None, choices=(0, 1),
                    help="with --guiding 1: Cycles' use_deterministic_guiding (its default 1, which slows training). Cycles "
                         "syncs it only with the Developer Extras (and Cycles Debug) preferences, which this option therefore turns on")
    return ap.parse_args(argv)


def look_at_matrix(pos, target, up):
    from mathutils import Matrix, Vector
    p, t, u = Vector(pos), Vector(target), Vector(up)
    f = (t - p).normalized()
    r = f.cross(u).normalized()
    uu = r.cross(f)
    # Blender cameras look along local -Z with local +Y up and +X right.
    m = Matrix.Identity(4)
    for i in range(3):
        m[i][0], m[i][1], m[i][2], m[i][3] = r[i], uu[i], -f[i], p[i]
    return m


def make_material(bpy, name, albedo, emission=None, one_sided=True):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    diff = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diff.inputs["Color"].default_value = (*albedo, 1.0)
    diff.inputs["Roughness"].default_value = 0.0
    front = diff.outputs["BSDF"]
    if emission is not None:
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = (*emission, 1.0)
        em.inputs["Strength"].default_value = 1.0
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(em.outputs["Emission"], add.inputs[0])
        nt.links.new(diff.outputs["BSDF"], add.inputs[1])
        front = add.outputs["Shader"]
        mat.cycles.emission_sampling = "FRONT" if one_sided else "FRONT_BACK"
    if one_sided:
        # Mitsuba semantics: BSDFs and area emitters are one-sided; back side is black.
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        black = nt.nodes.new("ShaderNodeBsdfDiffuse")
        black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        mix = nt.nodes.new("ShaderNodeMixShader")
        nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
        nt.links.new(front, mix.inputs[1])
        nt.links.new(black.outputs["BSDF"], mix.inputs[2])
        front = mix.outputs["Shader"]
    nt.links.new(front, out.inputs["Surface"])
    return mat


def build_scene(bpy, js, args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cyc = scene.cycles
    cyc.device = "CPU"
    cyc.samples = args.spp
    cyc.use_adaptive_sampling = args.adaptive_threshold > 0.0
    if cyc.use_adaptive_sampling:
        cyc.adaptive_threshold = args.adaptive_threshold
        cyc.adaptive_min_samples = args.adaptive_min_samples
    cyc.use_denoising = False
    cyc.seed = args.seed
    bounces = max(args.max_depth - 2, 0)
    cyc.max_bounces = bounces
    cyc.diffuse_bounces = bounces
    cyc.glossy_bounces = bounces
    cyc.transmission_bounces = bounces
    cyc.volume_bounces = 0
    cyc.transparent_max_bounces = bounces
    cyc.sample_clamp_direct = 0.0
    cyc.sample_clamp_indirect = 0.0     # Cycles defaults to 10: would bias the comparison
    cyc.light_sampling_threshold = 0.0
    cyc.use_light_tree = bool(args.light_tree)
    cyc.blur_glossy = 0.0
    cyc.caustics_reflective = True
    cyc.caustics_refractive = True
    # Path guiding (Open PGL, CPU only); property names as in CyclesRenderSettings.bl_rna.
    cyc.use_guiding = bool(args.guiding)
    cyc.use_surface_guiding = bool(args.guiding)
    cyc.use_volume_guiding = False
    if args.guiding_training_samples is not None:
        cyc.guiding_training_samples = args.guiding_training_samples
    if args.guiding_deterministic is not None:
        cyc.use_deterministic_guiding = bool(args.guiding_deterministic)
        # Cycles' sync reads use_deterministic_guiding (and the other guiding developer settings,
        # left at their defaults here) only with use_developer_ui, which BlenderSession takes
        # from the Developer Extras and Cycles Debug preferences.
        prefs = bpy.context.preferences
        prefs.view.show_developer_ui = True
        if hasattr(prefs.experimental, "use_cycles_debug"):
            prefs.experimental.use_cycles_debug = True
    film = js["film"]
    filt = (args.filter or film.get("pixel_filter", "box")).lower()
    if filt == "box":
        cyc.pixel_filter_type = "BOX"
        cyc.filter_width = 1.0
    elif filt == "gaussian":
        cyc.pixel_filter_type = "GAUSSIAN"
        cyc.filter_width = 1.5
    else:
        cyc.pixel_filter_type = "BLACKMAN_HARRIS"
        cyc.filter_width = 1.5

    W, H = args.res if args.res else (film["width"], film["height"])
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 100
    r.threads_mode = "FIXED"
    r.threads = args.threads
    r.film_transparent = False
    r.use_persistent_data = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0

    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Color"].default_value = (0, 0, 0, 1)
        bg.inputs["Strength"].default_value = 0.0
    scene.world = world

    cam = js["camera"]
    cd = bpy.data.cameras.new("camera")
    cd.type = "PERSP"
    cd.lens_unit = "FOV"
    axis = cam.get("fov_axis", "smaller")
    if axis == "x" or (axis == "smaller" and W <= H) or (axis == "larger" and W >= H):
        cd.sensor_fit = "HORIZONTAL"
    else:
        cd.sensor_fit = "VERTICAL"
    cd.angle = math.radians(cam["fov_deg"])
    cd.clip_start = cam.get("near_clip", 1e-3)
    cd.clip_end = cam.get("far_clip", 1e4)
    co = bpy.data.objects.new("camera", cd)
    scene.collection.objects.link(co)
    co.matrix_world = look_at_matrix(cam["position"], cam["look_at"], cam["up"])
    scene.camera = co

    vl = scene.view_layers[0]
    vl.use_pass_combined = True
    for p in ("diffuse_direct", "diffuse_indirect", "diffuse_color",
              "glossy_direct", "glossy_indirect", "glossy_color", "emit"):
        setattr(vl, "use_pass_" + p, not args.beauty_only)

    one_sided = not args.two_sided
    lightgroups = []
    for obj in js["objects"]:
        verts, faces = [], []
        for t in obj["triangles"]:
            b = len(verts)
            verts.extend(tuple(v) for v in t)
            faces.append((b, b + 1, b + 2))
        me = bpy.data.meshes.new(obj["name"])
        me.from_pydata(verts, [], faces)
        me.update()
        for poly in me.polygons:
            poly.use_smooth = False
        em = obj.get("emitter")
        if em is not None:
            assert em["type"] == "area"
            mat = make_material(bpy, "mat_" + obj["name"], js["materials"][obj["material"]]["albedo"],
                                emission=em["radiance"], one_sided=one_sided and not em.get("two_sided", False))
        else:
            mat = make_material(bpy, "mat_" + obj["material"] + "_" + obj["name"],
                                js["materials"][obj["material"]]["albedo"], one_sided=one_sided)
        me.materials.append(mat)
        ob = bpy.data.objects.new(obj["name"], me)
        scene.collection.objects.link(ob)
        if em is not None and not args.beauty_only:
            lg = obj["name"]
            vl.lightgroups.add(name=lg)
            ob.lightgroup = lg
            lightgroups.append(lg)
    return scene, (W, H), lightgroups, bounces


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    args = parse(argv)
    import bpy
    with open(args.json) as f:
        js = json.load(f)
    t0 = time.perf_counter()
    scene, (W, H), lightgroups, bounces = build_scene(bpy, js, args)
    t_build = time.perf_counter() - t0
    prefix = os.path.abspath(args.out or os.path.join(HERE, "out", f"cycles_{args.spp}spp_d{args.max_depth}"))
    os.makedirs(os.path.dirname(prefix), exist_ok=True)

    imf = scene.render.image_settings
    if args.beauty_only:
        # One RGBA layer (benches/peer/efficiency.sh reads it like the other renderers').
        imf.media_type = "IMAGE"
        imf.file_format = "OPEN_EXR"
    else:
        imf.media_type = "MULTI_LAYER_IMAGE"
        imf.file_format = "OPEN_EXR_MULTILAYER"
    imf.color_depth = "32"
    imf.exr_codec = "ZIP"
    scene.render.filepath = prefix + ".exr"
    scene.render.use_file_extension = False

    print(f"blender {bpy.app.version_string} cycles CPU threads={scene.render.threads} res={W}x{H} spp={args.spp} "
          f"max_depth={args.max_depth} (max_bounces={bounces}) filter={scene.cycles.pixel_filter_type} "
          f"light_tree={scene.cycles.use_light_tree} one_sided={not args.two_sided} lightgroups={lightgroups}")
    c = scene.cycles
    print(f"guiding={int(c.use_guiding)} surface={int(c.use_surface_guiding)} volume={int(c.use_volume_guiding)} "
          f"training_samples={c.guiding_training_samples} deterministic={int(c.use_deterministic_guiding)} "
          f"distribution={c.guiding_distribution_type} directional={c.guiding_directional_sampling_type}")
    print(f"build_s={t_build:.3f}")
    if args.save_blend:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save_blend))

    nsamples = W * H * args.spp
    times, cpus = [], []
    for rep in range(args.repeat):
        last = rep == args.repeat - 1
        t, c = time.perf_counter(), time.process_time()
        bpy.ops.render.render(write_still=last)
        dt = time.perf_counter() - t
        times.append(dt)
        cpus.append(time.process_time() - c)  # all render threads' CPU seconds
        print(f"run={rep} render_s={dt:.3f} (incl. scene sync/BVH{' + EXR write' if last else ''}) "
              f"Msamples_per_s={nsamples / dt / 1e6:.3f}")
    best = min(times)
    print(f"RESULT renderer=cycles guiding={args.guiding} spp={args.spp} max_depth={args.max_depth} threads={args.threads} "
          f"first_s={times[0]:.3f} best_s={best:.3f} best_cpu_s={cpus[times.index(best)]:.3f} Msamples_per_s_best={nsamples / best / 1e6:.3f}")
    print("wrote", prefix + ".exr")

    # PNG preview of the combined pass
    img = bpy.data.images.get("Render Result")
    if img is not None:
        imf.media_type = "IMAGE"
        imf.file_format = "PNG"
        imf.color_depth = "8"
        imf.color_mode = "RGB"
        img.save_render(prefix + ".png", scene=scene)
        print("wrote", prefix + ".png")


if __name__ == "__main__":
    main()
