"""Blender scene pieces shared by the bench scripts that build glTF shots with Blender as a
Python module (`bpy`, /work/venv311 or `pip install bpy==5.0.1`). Import it where bpy is
available:

    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    from benchlib.blender import add_light, image_material
"""

import math

import bpy


def add_light(scene, name, kind, energy, location=(0, 0, 5), rotation=(0, 0, 0), color=(1, 1, 1)):
    """A POINT, SPOT or SUN light linked into `scene`, with hard shadows (point and spot
    size 0, sun angle 0); `rotation` in radians. Returns the object."""
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    data.color = color
    if kind in ("POINT", "SPOT"):
        data.shadow_soft_size = 0.0
    if kind == "SUN":
        data.angle = 0.0
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    obj.rotation_euler = rotation
    scene.collection.objects.link(obj)
    return obj


def image_material(name, image, roughness=0.8):
    """A Principled BSDF material whose base colour is `image` (a bpy image)."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = image
    bsdf = nt.nodes["Principled BSDF"]
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = roughness
    return m


def principled(name, color, metallic=0.0, roughness=0.5, transmission=0.0, ior=1.5):
    """A Principled BSDF material of linear RGB `color`."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    b = m.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (*color, 1.0)
    b.inputs["Metallic"].default_value = metallic
    b.inputs["Roughness"].default_value = roughness
    b.inputs["Transmission Weight"].default_value = transmission
    b.inputs["IOR"].default_value = ior
    return m


def black_world(scene):
    """A world that emits nothing, so the scene's own lights are all there is."""
    w = bpy.data.worlds.new("black")
    w.use_nodes = True
    w.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = w


def add_camera(scene, name, fov_y_degrees, location, rotation):
    """`scene`'s camera: a vertical field of view in degrees, `rotation` in radians."""
    data = bpy.data.cameras.new(name)
    data.lens_unit = "FOV"
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(fov_y_degrees)
    cam = bpy.data.objects.new(name, data)
    scene.collection.objects.link(cam)
    cam.location = location
    cam.rotation_euler = rotation
    scene.camera = cam
    return cam
