"""Builds a small scene in Blender and exports it as glTF 2.0 binary (.glb).

Run headless: blender --background --factory-startup --python tests/blender/export_scene.py -- OUT.glb

The scene (Blender is z-up; the exporter turns it to glTF's y-up, so Blender (x, y, z) is glTF
(x, z, -y)): a grey floor plane, a red rough sphere left, a gold metal cube right, a small
emissive cube at the back, a camera in front looking at the sphere and cube with a 16:9 image
(640x360), a point light, a spot light and a sun. tests/gltf_scene.rs renders it and checks
where each object lands in the image.
"""
import math
import sys

import bpy
from mathutils import Vector

out = sys.argv[sys.argv.index("--") + 1]

# An empty scene (factory startup has a cube, a camera and a light).
bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()
for block in (bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras):
    for item in list(block):
        block.remove(item)


def material(name, color, roughness, metallic, emission=None, strength=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return m


def place(obj, name, mat):
    obj.name = name
    obj.data.materials.append(mat)


bpy.ops.mesh.primitive_plane_add(size=8, location=(0, 0, 0))
place(bpy.context.object, "Floor", material("Floor", (0.6, 0.6, 0.6), 0.8, 0.0))

bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(-0.9, 0, 0.6), segments=32, ring_count=16)
place(bpy.context.object, "RedBall", material("Red", (0.8, 0.05, 0.03), 0.4, 0.0))
bpy.ops.object.shade_smooth()

bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.9, 0, 0.5), rotation=(0, 0, math.radians(30)))
place(bpy.context.object, "GoldCube", material("Gold", (1.0, 0.77, 0.34), 0.3, 1.0))

bpy.ops.mesh.primitive_cube_add(size=0.4, location=(0, 1.6, 0.2))
place(bpy.context.object, "Lamp", material("Glow", (1, 1, 1), 0.5, 0.0, emission=(1.0, 0.9, 0.6), strength=4.0))

# Camera: 4 units in front (Blender -y), a little above, looking at (0, 0, 0.5).
bpy.ops.object.camera_add(location=(0, -4.5, 1.6))
cam = bpy.context.object
cam.name = "Camera"
cam.rotation_euler = (Vector((0, 0, 0.5)) - cam.location).to_track_quat("-Z", "Y").to_euler()
cam.data.lens = 35
bpy.context.scene.camera = cam
bpy.context.scene.render.resolution_x = 640
bpy.context.scene.render.resolution_y = 360

bpy.ops.object.light_add(type="POINT", location=(-2, -2, 3))
bpy.context.object.name = "Bulb"
bpy.context.object.data.energy = 300.0  # W

bpy.ops.object.light_add(type="SPOT", location=(2, -2, 3))
spot = bpy.context.object
spot.name = "Spot"
spot.data.energy = 400.0
spot.data.spot_size = math.radians(50)
spot.data.spot_blend = 0.2
spot.rotation_euler = (Vector((0.9, 0, 0.5)) - spot.location).to_track_quat("-Z", "Y").to_euler()

bpy.ops.object.light_add(type="SUN", location=(0, 0, 5), rotation=(math.radians(40), 0, math.radians(30)))
bpy.context.object.name = "Sun"
bpy.context.object.data.energy = 2.0  # W/m^2

bpy.ops.export_scene.gltf(
    filepath=out,
    export_format="GLB",
    export_cameras=True,
    export_lights=True,
    export_apply=True,
)
print("exported", out)
