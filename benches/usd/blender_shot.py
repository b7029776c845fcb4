"""Builds the USD held-out shot of issue 28 in Blender and exports it with Blender's own USD
exporter, then writes a TD's layer over it: the stage metrics (only the root layer's
count), RenderSettings, a product, LPE and raw RenderVars, the object tag `balls` on the
chrome ball (Karma) and the gold ball (RenderMan), and light groups on the key (RenderMan)
and the sun (Karma).

Run with Blender as a Python module (not a CI dependency):

    /path/to/python3.11 benches/usd/blender_shot.py OUT_DIR
    lightpath render OUT_DIR/td.usda --spp 64 --light-groups --cryptomatte -o lp.exr
    /path/to/python3.11 benches/usd/cycles_shot.py OUT_DIR/td.usda -o cycles.exr
    python benches/usd/compare.py cycles.exr lp.exr (flags: see compare.py)

Writes OUT_DIR/shot.usdc (Blender's export: textured crate, two Suzannes, chrome and gold
balls, rect, sphere and distant lights and the world as a dome light) and OUT_DIR/td.usda
(the TD's layer, sublayering the export).
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from benchlib.blender import principled  # noqa: E402

out_dir = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "usd-shot")
os.makedirs(out_dir, exist_ok=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def checker(name, n=64, cells=8):
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
    nt.links.new(tex.outputs["Color"], nt.nodes["Principled BSDF"].inputs["Base Color"])
    nt.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.8
    return m


def named(name, material):
    o = bpy.context.object
    o.name = name
    o.data.materials.append(material)
    return o


bpy.ops.mesh.primitive_plane_add(size=10)
named("floor", principled("floor_mat", (0.6, 0.6, 0.6), roughness=0.9))
bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-1.6, 0.4, 0.5), rotation=(0, 0, 0.4))
named("crate", textured("crate_mat", checker("checker")))
for i, x in enumerate((-0.2, 1.0)):
    bpy.ops.mesh.primitive_monkey_add(size=0.8, location=(x, 1.2, 0.55), rotation=(0, 0, math.radians(180)))
    named(f"suzanne{i}", principled(f"suzanne_mat{i}", (0.8, 0.3, 0.2), roughness=0.4))
    bpy.ops.object.shade_smooth()
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.45, location=(0.2, -0.5, 0.45), segments=48, ring_count=24)
named("chrome", principled("chrome_mat", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.05))
bpy.ops.object.shade_smooth()
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.45, location=(1.4, -0.4, 0.45), segments=48, ring_count=24)
named("gold", principled("gold_mat", (1.0, 0.77, 0.34), metallic=1.0, roughness=0.2))
bpy.ops.object.shade_smooth()

cam_data = bpy.data.cameras.new("shot")
cam = bpy.data.objects.new("shot", cam_data)
scene.collection.objects.link(cam)
cam.location = (0.0, -7.0, 3.2)
cam.rotation_euler = (math.radians(67.0), 0.0, 0.0)
scene.camera = cam
scene.render.resolution_x, scene.render.resolution_y = 320, 240


def light(name, kind, energy, location, rotation=(0, 0, 0)):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    obj = bpy.data.objects.new(name, data)
    obj.location, obj.rotation_euler = location, rotation
    scene.collection.objects.link(obj)
    return obj


key = light("key", "AREA", 300.0, (2.5, -2.0, 4.0), rotation=(math.radians(35), 0, math.radians(50)))
key.data.size = 1.5
bulb = light("bulb", "POINT", 150.0, (-2.5, -1.0, 2.5))
bulb.data.shadow_soft_size = 0.2
sun = light("sun", "SUN", 1.0, (0, 0, 6), rotation=(math.radians(40), math.radians(20), 0))
world = bpy.data.worlds.new("sky")
world.use_nodes = True
bg = world.node_tree.nodes["Background"]
bg.inputs["Color"].default_value = (0.6, 0.7, 0.9, 1.0)
bg.inputs["Strength"].default_value = 0.15
scene.world = world

bpy.ops.wm.usd_export(filepath=os.path.join(out_dir, "shot.usdc"), export_lights=True,
                      export_cameras=True, export_materials=True)

td = """#usda 1.0
(
    subLayers = [@shot.usdc@]
    renderSettingsPrimPath = "/Render/Settings"
    metersPerUnit = 1
    upAxis = "Z"
)
over "root"
{
    over "chrome"
    {
        string primvars:karma:object:lpetag = "balls"
    }
    over "gold"
    {
        string primvars:ri:attributes:identifier:lpegroup = "balls"
    }
    over "key"
    {
        over "key"
        {
            string ri:light:lightGroup = "keygroup"
        }
    }
    over "sun"
    {
        over "sun"
        {
            string karma:light:lpetag = "sungroup"
        }
    }
}
def Scope "Render"
{
    def RenderSettings "Settings"
    {
        rel products = </Render/Beauty>
        uniform int2 resolution = (320, 240)
    }
    def RenderProduct "Beauty"
    {
        token productName = "td.exr"
        rel camera = </root/shot/shot>
        rel orderedVars = [</Render/Vars/Ci>, </Render/Vars/diffuse_key>, </Render/Vars/balls>, </Render/Vars/sun>, </Render/Vars/N>]
    }
    def Scope "Vars"
    {
        def RenderVar "Ci"
        {
            uniform string sourceName = "Ci"
            uniform token sourceType = "raw"
        }
        def RenderVar "diffuse_key"
        {
            uniform string sourceName = "C<RD>[<L.'keygroup'>O]"
            uniform token sourceType = "lpe"
        }
        def RenderVar "balls"
        {
            uniform string sourceName = "lpe:C<.'balls'>.*[<L.>O]"
            uniform token sourceType = "lpe"
        }
        def RenderVar "sun"
        {
            uniform string sourceName = "C.*<L.'sungroup'>"
            uniform token sourceType = "lpe"
        }
        def RenderVar "N"
        {
            uniform string sourceName = "normal"
            uniform token sourceType = "raw"
        }
    }
}
"""
with open(os.path.join(out_dir, "td.usda"), "w") as f:
    f.write(td)
print("wrote", out_dir)
