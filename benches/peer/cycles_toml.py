#!/usr/bin/env python3
"""Blender Cycles (CPU) renders of Lightpath's simple TOML bench scenes, for peer ratios
(benches/guiding/portals_vs_cycles.py).

    /work/venv311/bin/python cycles_toml.py SCENE.toml OUT.exr --spp 64 --seed 1 [--no-portals]

Reads what the guiding benches' interiors use: `quad`, `cube` and `sphere` objects;
`diffuse`, `plastic` (Principled, specular 0.5, the given roughness) and `conductor`
(Principled metallic) materials; a `dome` of constant radiance with `portals` (Cycles
area lights marked as portals, facing into the room), and `distant` lights (Cycles suns).
Lightpath is Y-up, Blender Z-up: (x, y, z) becomes (x, -z, y). The depth convention is
Mitsuba's, as Lightpath's: max_depth segments, Cycles max_bounces = max_depth - 2. Box
filter 1 px, no clamping, no denoising, no adaptive sampling, no Filter Glossy. Prints
the render's wall seconds (scene sync and BVH included, Blender's start-up not).
"""
import argparse
import math
import sys
import time
import tomllib

import bpy
import mathutils


def v(p):
    return mathutils.Vector((p[0], -p[2], p[1]))


def material(name, m):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    kind = m.get("type", "diffuse")
    if kind == "diffuse":
        n = nt.nodes.new("ShaderNodeBsdfDiffuse")
        n.inputs["Color"].default_value = (*m.get("albedo", [0.8] * 3), 1.0)
        nt.links.new(n.outputs["BSDF"], out.inputs["Surface"])
    else:
        n = nt.nodes.new("ShaderNodeBsdfPrincipled")
        if kind == "conductor":
            n.inputs["Base Color"].default_value = (*m.get("f0", [0.9] * 3), 1.0)
            n.inputs["Metallic"].default_value = 1.0
        else:
            n.inputs["Base Color"].default_value = (*m.get("albedo", [0.8] * 3), 1.0)
        n.inputs["Roughness"].default_value = m.get("roughness", 0.0)
        nt.links.new(n.outputs["BSDF"], out.inputs["Surface"])
    return mat


def mesh_object(name, verts, faces, mat):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(x) for x in verts], [], faces)
    me.update()
    ob = bpy.data.objects.new(name, me)
    ob.data.materials.append(mat)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def build(scene_toml, args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    cyc = sc.cycles
    cyc.device = "CPU"
    cyc.samples = args.spp
    cyc.use_adaptive_sampling = False
    cyc.use_denoising = False
    cyc.seed = args.seed
    depth = scene_toml.get("render", {}).get("max_depth", 8)
    b = max(depth - 2, 0)
    cyc.max_bounces = cyc.diffuse_bounces = cyc.glossy_bounces = b
    cyc.transmission_bounces = cyc.transparent_max_bounces = b
    cyc.volume_bounces = 0
    cyc.sample_clamp_direct = cyc.sample_clamp_indirect = 0.0
    cyc.light_sampling_threshold = 0.0
    cyc.blur_glossy = 0.0
    cyc.pixel_filter_type = "BOX"
    cyc.filter_width = 1.0
    w, h = scene_toml.get("film", {}).get("resolution", [160, 120])
    r = sc.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.threads_mode = "FIXED"
    r.threads = args.threads
    r.image_settings.media_type = "MULTI_LAYER_IMAGE"
    r.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    r.image_settings.color_depth = "32"
    sc.view_settings.view_transform = "Standard"
    mats = {k: material(k, m) for k, m in scene_toml.get("materials", {}).items()}
    for i, o in enumerate(scene_toml.get("objects", [])):
        mat = mats[o["material"]]
        shape = o["shape"]
        if shape == "quad":
            mesh_object(f"o{i}", [v(c) for c in o["corners"]], [(0, 1, 2, 3)], mat)
        elif shape == "cube":
            s = o.get("scale", [1, 1, 1])
            s = s if isinstance(s, list) else [s] * 3
            t = o.get("translate", [0, 0, 0])
            corners = [[t[0] + sx * s[0], t[1] + sy * s[1], t[2] + sz * s[2]]
                       for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
            faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
            mesh_object(f"o{i}", [v(c) for c in corners], faces, mat)
        elif shape == "sphere":
            bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=o["radius"],
                                                 location=v(o["center"]))
            ob = bpy.context.active_object
            bpy.ops.object.shade_smooth()
            ob.data.materials.append(mat)
        else:
            sys.exit(f"shape {shape} is not read here")
    world = bpy.data.worlds.new("world")
    sc.world = world
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0, 0, 0, 1)
    for i, l in enumerate(scene_toml.get("lights", [])):
        if l["type"] == "dome":
            bg.inputs["Color"].default_value = (*l.get("radiance", [1, 1, 1]), 1)
            bg.inputs["Strength"].default_value = 1.0
            world.cycles_visibility.camera = l.get("camera_visible", True)
            if args.no_portals:
                continue
            for k, c in enumerate(l.get("portals", [])):
                p0, p1, p3 = v(c[0]), v(c[1]), v(c[3])
                e1, e2 = p1 - p0, p3 - p0
                centre = p0 + 0.5 * (e1 + e2)
                normal = e1.cross(e2).normalized()
                # Face into the room: towards the camera's side of the portal's plane.
                cam = v(scene_toml["camera"]["position"])
                if normal.dot(cam - centre) < 0:
                    normal = -normal
                data = bpy.data.lights.new(f"portal{k}", "AREA")
                data.shape = "RECTANGLE"
                data.size, data.size_y = e1.length, e2.length
                data.cycles.is_portal = True
                ob = bpy.data.objects.new(f"portal{k}", data)
                # The area light emits along its local -Z, its local X along e1.
                z = -normal
                x = e1.normalized()
                y = z.cross(x)
                ob.matrix_world = mathutils.Matrix((
                    (x[0], y[0], z[0], centre[0]),
                    (x[1], y[1], z[1], centre[1]),
                    (x[2], y[2], z[2], centre[2]),
                    (0, 0, 0, 1)))
                sc.collection.objects.link(ob)
        elif l["type"] == "distant":
            data = bpy.data.lights.new(f"sun{i}", "SUN")
            data.energy = max(l.get("irradiance", [1, 1, 1]))
            irr = l.get("irradiance", [1, 1, 1])
            data.color = [c / data.energy for c in irr]
            data.angle = math.radians(l.get("angle", 0.0))
            ob = bpy.data.objects.new(f"sun{i}", data)
            d = v(l["direction"]).normalized()
            ob.rotation_euler = (-d).to_track_quat("Z", "Y").to_euler()
            sc.collection.objects.link(ob)
        else:
            sys.exit(f"light {l['type']} is not read here")
    cam = scene_toml["camera"]
    cd = bpy.data.cameras.new("cam")
    aspect = w / h
    fov = math.radians(cam.get("fov", 40))
    cd.sensor_fit = "VERTICAL" if w >= h else "HORIZONTAL"
    cd.angle = fov
    co = bpy.data.objects.new("cam", cd)
    pos, at = v(cam["position"]), v(cam["look_at"])
    co.location = pos
    co.rotation_euler = (pos - at).to_track_quat("Z", "Y").to_euler()
    sc.collection.objects.link(co)
    sc.camera = co
    del aspect


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--no-portals", action="store_true")
    args = ap.parse_args(argv)
    with open(args.scene, "rb") as f:
        scene_toml = tomllib.load(f)
    build(scene_toml, args)
    bpy.context.scene.render.filepath = args.out
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    print(f"RENDER_SECONDS {time.time() - t0:.3f}")


if __name__ == "__main__":
    main()
