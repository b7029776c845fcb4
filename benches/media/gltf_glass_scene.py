"""Builds the glTF absorbing-glass check (issue 27) in Blender and exports it as .glb:
two smooth glass balls (ior 1.5) with KHR_materials_volume interiors on a grey floor before
a grey back wall, under an emissive quad (a mesh light, which both renderers sample, so
the light the balls focus onto the floor is reachable by ordinary path tracing).

    /work/venv311/bin/python benches/media/gltf_glass_scene.py OUT.glb   # bpy==5.0.1

The left ball is the green glass of the cornell check (attenuationColor 0.2, 0.8, 0.3 at
attenuationDistance 0.5); the right one is an amber glass at a colour and distance used by
no other test (0.9, 0.55, 0.15 at 1.2). The interiors are authored the way the exporter
reads them: a Volume Absorption on the Material Output (Color = attenuationColor, Density =
1 / attenuationDistance) and a "glTF Material Output" group whose Thickness is the ball's
diameter. `gltf_glass.py` renders the file with Lightpath and Cycles and compares."""
import math
import os
import sys

import bpy

out = os.path.abspath(sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else sys.argv[1])
BALLS = {  # name: (centre x, attenuation colour, attenuation distance)
    "green": (-0.6, (0.2, 0.8, 0.3), 0.5),
    "amber": (0.6, (0.9, 0.55, 0.15), 1.2),
}
RADIUS = 0.5

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def principled(name, color, roughness=0.5, transmission=0.0, emission=None, strength=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (*color, 1.0)
    b.inputs["Roughness"].default_value = roughness
    b.inputs["Transmission Weight"].default_value = transmission
    b.inputs["IOR"].default_value = 1.5
    if emission is not None:
        b.inputs["Emission Color"].default_value = (*emission, 1.0)
        b.inputs["Emission Strength"].default_value = strength
    return m


def gltf_output_group():
    """The node group the glTF exporter reads Thickness from (its importer makes the same)."""
    g = bpy.data.node_groups.get("glTF Material Output")
    if g is None:
        g = bpy.data.node_groups.new("glTF Material Output", "ShaderNodeTree")
        g.interface.new_socket("Thickness", in_out="INPUT", socket_type="NodeSocketFloat")
    return g


def absorbing_glass(name, color, distance):
    m = principled(name, (1, 1, 1), roughness=0.0, transmission=1.0)
    nt = m.node_tree
    vol = nt.nodes.new("ShaderNodeVolumeAbsorption")
    vol.inputs["Color"].default_value = (*color, 1.0)
    vol.inputs["Density"].default_value = 1.0 / distance
    nt.links.new(vol.outputs["Volume"], nt.nodes["Material Output"].inputs["Volume"])
    grp = nt.nodes.new("ShaderNodeGroup")
    grp.node_tree = gltf_output_group()
    grp.inputs["Thickness"].default_value = 2 * RADIUS
    return m


def mesh(obj, name, material):
    obj.name = name
    obj.data.name = name
    obj.data.materials.append(material)
    return obj


bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
mesh(bpy.context.object, "floor", principled("floor_mat", (0.7, 0.7, 0.7), roughness=1.0))
bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 2.0, 4.0), rotation=(math.radians(90), 0, 0))
mesh(bpy.context.object, "wall", principled("wall_mat", (0.5, 0.5, 0.5), roughness=1.0))
# The light: a 2 × 2 quad 3 above the floor facing down (a plane's normal is +z: flipped).
bpy.ops.mesh.primitive_plane_add(size=2, location=(0, -0.5, 3.0), rotation=(math.radians(180), 0, 0))
mesh(bpy.context.object, "light", principled("light_mat", (0, 0, 0), roughness=1.0,
                                             emission=(1, 1, 1), strength=6.0))
for name, (x, color, distance) in BALLS.items():
    bpy.ops.mesh.primitive_uv_sphere_add(radius=RADIUS, location=(x, 0, RADIUS), segments=64, ring_count=32)
    bpy.ops.object.shade_smooth()
    mesh(bpy.context.object, name, absorbing_glass(name + "_glass", color, distance))

cam_data = bpy.data.cameras.new("shot")
cam_data.sensor_fit = "VERTICAL"
cam_data.angle_y = math.radians(30.0)
cam = bpy.data.objects.new("shot", cam_data)
scene.collection.objects.link(cam)
cam.location = (0.0, -5.0, 1.6)
cam.rotation_euler = (math.radians(78.0), 0.0, 0.0)
scene.camera = cam

os.makedirs(os.path.dirname(out), exist_ok=True)
bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_cameras=True, export_yup=True)
print("wrote", out)
