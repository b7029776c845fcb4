"""Builds the glTF comparison scene in Blender, exports it as .glb and renders a Cycles
reference with one light-group pass per light.

Run with Blender as a Python module (not a CI dependency):

    pip install bpy==5.0.1 OpenEXR numpy        # Python 3.11
    python benches/gltf/blender_scene.py OUT_DIR [SPP]

Writes OUT_DIR/scene.glb and OUT_DIR/cycles.exr (multilayer: Combined and
Combined_<group> per light group). `compare.py` renders the .glb with Lightpath and
compares the two.
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.blender import add_camera, add_light, principled  # noqa: E402

out_dir = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "gltf-compare")
spp = int(sys.argv[2]) if len(sys.argv) > 2 else 256
os.makedirs(out_dir, exist_ok=True)
WIDTH, HEIGHT = 320, 240

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def checker_image(name, n=64, cells=8):
    img = bpy.data.images.new(name, n, n, alpha=False)
    px = []
    for y in range(n):
        for x in range(n):
            on = ((x * cells // n) + (y * cells // n)) % 2 == 0
            px += [0.9, 0.6, 0.1, 1.0] if on else [0.1, 0.2, 0.8, 1.0]
    img.pixels = px
    img.filepath_raw = os.path.join(out_dir, name + ".png")
    img.file_format = "PNG"
    img.save()
    return img


def textured(name, img):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = img
    tex.interpolation = "Linear"
    nt.links.new(tex.outputs["Color"], nt.nodes["Principled BSDF"].inputs["Base Color"])
    nt.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.8
    return m


def add(obj, material, parent=None):
    obj.data.materials.append(material)
    if parent is not None:
        obj.parent = parent
    return obj


# Geometry: a floor, a textured crate, and a 'props' collection node holding glass and chrome.
bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
floor = bpy.context.object
floor.name = "floor"
add(floor, principled("floor_mat", (0.6, 0.6, 0.6), roughness=0.9))

bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-1.3, 0.2, 0.5), rotation=(0, 0, 0.4))
crate = bpy.context.object
crate.name = "crate"
add(crate, textured("crate_mat", checker_image("checker")))

bpy.ops.object.empty_add(location=(0.6, 0, 0))
props = bpy.context.object
props.name = "props"

bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(0.0, -0.4, 0.5), segments=48, ring_count=24)
glass = bpy.context.object
glass.name = "glass"
bpy.ops.object.shade_smooth()
add(glass, principled("glass_mat", (1, 1, 1), roughness=0.0, transmission=1.0, ior=1.5), props)
glass.location = (0.0, -0.4, 0.5)

bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(1.1, 0.7, 0.5), segments=48, ring_count=24)
chrome = bpy.context.object
chrome.name = "chrome"
bpy.ops.object.shade_smooth()
add(chrome, principled("chrome_mat", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.0), props)
chrome.location = (0.5, 0.7, 0.5)

# Camera.
add_camera(scene, "shot", 40.0, (0.0, -6.0, 3.0), (math.radians(65.0), 0.0, 0.0))

# Lights: point, spot and sun, each its own light group; no world light.
point = add_light(scene, "key", "POINT", 400.0, (2.5, -1.5, 3.0), color=(1.0, 0.9, 0.8))
spot = add_light(scene, "spot", "SPOT", 800.0, (-2.0, -2.0, 4.0), rotation=(math.radians(35), 0, math.radians(-45)))
spot.data.spot_size = math.radians(50)
spot.data.spot_blend = 0.3
sun = add_light(scene, "sun", "SUN", 1.5, (0, 0, 5), rotation=(math.radians(40), math.radians(20), 0), color=(0.8, 0.9, 1.0))

world = bpy.data.worlds.new("black")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
scene.world = world

bpy.ops.export_scene.gltf(
    filepath=os.path.join(out_dir, "scene.glb"),
    export_format="GLB",
    export_cameras=True,
    export_lights=True,
    export_extras=True,
    export_yup=True,
)

# Cycles reference: light groups as Cycles defines them, one per light.
vl = scene.view_layers[0]
for o in (point, spot, sun):
    vl.lightgroups.add(name=o.name)
    o.lightgroup = o.name
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = spp
scene.cycles.use_denoising = False
scene.cycles.max_bounces = 8
scene.cycles.caustics_reflective = True
scene.cycles.caustics_refractive = True
scene.cycles.sample_clamp_indirect = 0.0
scene.cycles.blur_glossy = 0.0
scene.render.film_transparent = True
scene.render.resolution_x = WIDTH
scene.render.resolution_y = HEIGHT
scene.render.resolution_percentage = 100
scene.render.filter_size = 0.01  # a box-like pixel filter, as Lightpath's default
scene.view_settings.view_transform = "Standard"
scene.render.image_settings.media_type = "MULTI_LAYER_IMAGE"
scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = os.path.join(out_dir, "cycles.exr")
bpy.ops.render.render(write_still=True)
print("wrote", out_dir)
