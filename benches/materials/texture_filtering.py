"""Why the checker crate of benches/peer/real_scenes.py is ~6 % brighter in Lightpath than in
Cycles: Cycles interpolates 8-bit sRGB textures before decoding them (kernel/svm/image.h,
NODE_IMAGE_COMPRESS_AS_SRGB), Lightpath after (material/texture.rs).

    python benches/materials/texture_filtering.py OUT_DIR LIGHTPATH_BINARY [--spp 256] [--res 128]
    python benches/materials/texture_filtering.py cycles FILE.glb OUT.exr SPP TEXTURES [--real-shot]

The first builds OUT_DIR/patches.glb in Blender (a 2×2 plane seen from above under a sun at
30°, a 64×64 PNG of 16 patches: greys of known sRGB values, the crate's orange and blue, and
orange/blue checkers of 1-, 2- and 8-texel cells; Principled roughness 0.8), renders it with
Lightpath and with Cycles three ways (TEXTURES: `bytes`, the .glb imported as is; `linear`,
each image replaced by a float image of its exactly decoded values, so that Cycles
interpolates linear values; `closest`, the image node's interpolation Closest), and prints
each patch's mean (the middle half of the patch) and Lambert's a·E·cosθ/π for the decoded
texel (the specular layer adds ~0.02 to it).

`cycles` renders one file: with `--real-shot`, as real_scenes.py's cycles() does at its
matched settings (160×120, depth 16, Filter Glossy 1, no clamp, 2 threads, seed 1000), for
comparing the crate with Lightpath's reference there. Needs bpy 5.0.1, numpy, OpenEXR.
"""

import argparse
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.exr import channels, rgb  # noqa: E402

ORANGE, BLUE = (0.9, 0.6, 0.1), (0.1, 0.2, 0.8)
# The 4×4 patches, row by row from the image's first (Blender: bottom) row; "chkN" is an
# orange/blue checker of N-texel cells.
PATCHES = [(0.0,) * 3, (0.02,) * 3, (0.04,) * 3, (0.1,) * 3, (0.2,) * 3, (0.5,) * 3, (0.8,) * 3,
           (1.0,) * 3, ORANGE, BLUE, "chk2", "chk8", "chk1", (0.01,) * 3, (0.3,) * 3, (0.05,) * 3]
SUN_STRENGTH, SUN_TILT = 3.0, 30.0


def srgb_to_linear(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def texel(x, y):
    p = PATCHES[(y // 16) * 4 + x // 16]
    if isinstance(p, str):
        n = int(p[3:])
        p = ORANGE if (x // n + y // n) % 2 == 0 else BLUE
    return p


def build(out_dir, res):
    import bpy
    from benchlib.blender import image_material

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    img = bpy.data.images.new("patches", 64, 64, alpha=False)
    img.pixels = [v for y in range(64) for x in range(64) for v in (*texel(x, y), 1.0)]
    img.filepath_raw = f"{out_dir}/patches.png"
    img.file_format = "PNG"
    img.save()
    m = image_material("patch_mat", img, roughness=0.8)
    bpy.ops.mesh.primitive_plane_add(size=2, location=(0, 0, 0))
    bpy.context.object.name = "plane"
    bpy.context.object.data.materials.append(m)
    # From 10 units up, a vertical field of view of 2·atan(0.1) spans the plane.
    cd = bpy.data.cameras.new("cam")
    cd.lens_unit, cd.sensor_fit, cd.angle_y = "FOV", "VERTICAL", 2 * math.atan(0.1)
    cam = bpy.data.objects.new("cam", cd)
    sc.collection.objects.link(cam)
    cam.location = (0, 0, 10)
    sc.camera = cam
    sc.render.resolution_x = sc.render.resolution_y = res
    ld = bpy.data.lights.new("sun", "SUN")
    ld.energy, ld.angle = SUN_STRENGTH, 0.0
    sun = bpy.data.objects.new("sun", ld)
    sun.rotation_euler = (math.radians(SUN_TILT), 0, 0)
    sc.collection.objects.link(sun)
    bpy.ops.export_scene.gltf(filepath=f"{out_dir}/patches.glb", export_format="GLB",
                              export_cameras=True, export_lights=True, export_yup=True)


def cycles(glb, out, spp, textures, real_shot, res):
    """Renders GLB with Cycles, its image textures as imported (`bytes`), decoded to float
    (`linear`) or point-sampled (`closest`)."""
    import bpy
    from benchlib.blender import black_world

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(glb))
    sc.camera = [o for o in sc.objects if o.type == "CAMERA"][0]
    for m in bpy.data.materials:
        for n in (m.node_tree.nodes if m.node_tree else []):
            if n.type != "TEX_IMAGE" or n.image is None:
                continue
            if textures == "closest":
                n.interpolation = "Closest"
            elif textures == "linear":
                img = n.image
                px = np.array(img.pixels[:], dtype=np.float64).reshape(-1, 4)
                lin = bpy.data.images.new(img.name + "_linear", *img.size, alpha=True, float_buffer=True)
                lin.colorspace_settings.name = "Linear Rec.709"
                lin.pixels = np.concatenate([srgb_to_linear(px[:, :3]), px[:, 3:]], 1).ravel()
                lin.pack()
                n.image = lin
    black_world(sc)
    c = sc.cycles
    sc.render.engine = "CYCLES"
    c.device, c.samples, c.seed = "CPU", spp, 1000
    c.use_denoising = c.use_adaptive_sampling = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.caustics_reflective = c.caustics_refractive = True
    c.blur_glossy = 1.0 if real_shot else 0.0
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "transparent_max_bounces"):
        setattr(c, k, 16)
    sc.render.threads_mode, sc.render.threads = "FIXED", 2
    sc.render.resolution_x, sc.render.resolution_y = (160, 120) if real_shot else (res, res)
    sc.render.resolution_percentage = 100
    sc.view_layers[0].use_pass_object_index = True
    meshes = sorted([o for o in sc.objects if o.type == "MESH"], key=lambda o: o.name)
    for i, o in enumerate(meshes):
        o.pass_index = i + 1
    imf = sc.render.image_settings
    imf.media_type, imf.file_format, imf.color_depth = "MULTI_LAYER_IMAGE", "OPEN_EXR_MULTILAYER", "32"
    sc.render.filepath = os.path.abspath(out)
    bpy.ops.render.render(write_still=True)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "cycles":
        ap = argparse.ArgumentParser()
        ap.add_argument("step")
        ap.add_argument("glb")
        ap.add_argument("out")
        ap.add_argument("spp", type=int)
        ap.add_argument("textures", choices=["bytes", "linear", "closest"])
        ap.add_argument("--real-shot", action="store_true")
        ap.add_argument("--res", type=int, default=128)
        a = ap.parse_args()
        cycles(a.glb, a.out, a.spp, a.textures, a.real_shot, a.res)
        return
    ap = argparse.ArgumentParser()
    ap.add_argument("out_dir")
    ap.add_argument("binary")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--res", type=int, default=128)
    a = ap.parse_args()
    out = os.path.abspath(a.out_dir)
    os.makedirs(out, exist_ok=True)
    glb = f"{out}/patches.glb"
    if not os.path.exists(glb):
        subprocess.run([sys.executable, os.path.abspath(__file__), "build", out, str(a.res)], check=True,
                       capture_output=True)
    images = {}
    for mode in ("bytes", "linear", "closest"):
        exr = f"{out}/patches_cycles_{mode}.exr"
        if not os.path.exists(exr):
            subprocess.run([sys.executable, os.path.abspath(__file__), "cycles", glb, exr, str(a.spp), mode,
                            "--res", str(a.res)], check=True, capture_output=True)
        images[f"Cycles {mode}"] = rgb(channels(exr), "ViewLayer.Combined.")
    lp = f"{out}/patches_lightpath.exr"
    if not os.path.exists(lp):
        subprocess.run([a.binary, "render", glb, "-o", lp, "--quiet", "--aovs", "none", "--spp", str(a.spp),
                        "--resolution", f"{a.res}x{a.res}"], check=True)
    images["Lightpath"] = rgb(channels(lp), "")
    s = a.res // 4
    irradiance = SUN_STRENGTH * math.cos(math.radians(SUN_TILT))
    print(f"{a.spp} spp, {a.res}x{a.res}, patch means R G B; Lightpath's difference from each Cycles variant, %")
    print(f"{'patch':>16} | " + " | ".join(f"{k:>20}" for k in images) + " | LP/Cy bytes, linear, closest % (mean of RGB) | Lambert")
    for row in range(4):
        for col in range(4):
            # Image rows run top to bottom, the texture's from the bottom.
            p = PATCHES[(3 - row) * 4 + col]
            m = {k: v[row * s + s // 4:(row + 1) * s - s // 4, col * s + s // 4:(col + 1) * s - s // 4]
                 .reshape(-1, 3).mean(0) for k, v in images.items()}
            lp_mean = m["Lightpath"].mean()
            diffs = ", ".join(f"{100 * (lp_mean / m[f'Cycles {k}'].mean() - 1):+.1f}"
                              for k in ("bytes", "linear", "closest"))
            lam = "" if isinstance(p, str) else " ".join(
                f"{v:.4f}" for v in srgb_to_linear(np.round(np.array(p) * 255) / 255) * irradiance / math.pi)
            print(f"{str(p):>16} | " + " | ".join(" ".join(f"{v:.4f}" for v in x) for x in m.values())
                  + f" | {diffs} | {lam}")


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "build":
        build(sys.argv[2], int(sys.argv[3]))
    else:
        main()
