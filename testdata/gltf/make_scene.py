# Generates room.gltf + room.bin, the small animated glTF 2.0 test scene of
# `modestack render --scene testdata/gltf/room.gltf`, with Blender's own glTF
# exporter. Run from the repository root (Debian's blender package):
#
#     blender -b --factory-startup --python testdata/gltf/make_scene.py
#
# The scene (Blender units = metres, exported +Y up): a closed 3 x 2.5 x 3 m room
# (white floor, ceiling, back and front walls, red left wall, green right wall),
# a point light under the ceiling and a small emissive panel on the back wall, a
# box that slides across the floor while it turns, with a smaller box parented on
# top of it (node hierarchy), and a camera that moves from left to right, always
# looking at the middle of the room. 24 frames at 24 fps (scene extras "fps").
# Blender's exporter writes key times as frame / fps, so the shot is keyed on
# Blender frames 0-23: modestack's frame f (time (f - 1) / fps) is Blender frame f - 1.
# No .blend file is kept: this script is the source.
import math
import os

import bpy
from mathutils import Vector

OUT_DIR = os.path.dirname(os.path.abspath(__file__))
FIRST_FRAME, LAST_FRAME = 0, 23

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps = 24
scene.frame_start, scene.frame_end = FIRST_FRAME, LAST_FRAME
scene.render.resolution_x, scene.render.resolution_y = 320, 240
scene["fps"] = 24  # exported as scenes[0].extras.fps; modestack's default --fps


def material(name, colour, emission=None, strength=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Metallic"].default_value = 0.0
    bsdf.inputs["Roughness"].default_value = 1.0
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return mat


def plane(name, location, rotation, size, mat):
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=location, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    obj.scale = size
    obj.data.materials.append(mat)
    return obj


def box(name, location, size, mat):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=location)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    obj.scale = size
    obj.data.materials.append(mat)
    return obj


white = material("white", (0.73, 0.73, 0.73))
red = material("red", (0.63, 0.065, 0.05))
green = material("green", (0.14, 0.45, 0.091))
blue = material("blue", (0.1, 0.2, 0.6))
panel = material("panel", (0.8, 0.8, 0.8), emission=(1.0, 0.85, 0.6), strength=6.0)

# The room: x in [-1.5, 1.5], y (depth) in [-1.5, 1.5], z (up) in [0, 2.5]. The
# planes' normals face into the room.
H = 2.5
plane("floor", (0, 0, 0), (0, 0, 0), (3, 3, 1), white)
plane("ceiling", (0, 0, H), (math.pi, 0, 0), (3, 3, 1), white)
plane("back", (0, 1.5, H / 2), (math.pi / 2, 0, 0), (3, H, 1), white)
plane("front", (0, -1.5, H / 2), (-math.pi / 2, 0, 0), (3, H, 1), white)
plane("left", (-1.5, 0, H / 2), (0, math.pi / 2, 0), (H, 3, 1), red)
plane("right", (1.5, 0, H / 2), (0, -math.pi / 2, 0), (H, 3, 1), green)
plane("panel", (0, 1.49, 1.6), (math.pi / 2, 0, 0), (0.6, 0.3, 1), panel)

# The light: a point light of 60 W under the ceiling.
light_data = bpy.data.lights.new("lamp", type="POINT")
light_data.energy = 60.0
light_data.shadow_soft_size = 0.05
lamp = bpy.data.objects.new("lamp", light_data)
lamp.location = (0, 0, 2.2)
scene.collection.objects.link(lamp)

# The moving box, and a smaller box riding on it (a child node).
mover = box("mover", (-0.8, 0.2, 0.2), (0.4, 0.4, 0.4), white)
rider = box("rider", (0, 0, 0.75), (0.5, 0.5, 0.5), blue)  # in the mover's (scaled) space
rider.parent = mover
for frame, x, turn in ((FIRST_FRAME, -0.8, 0.0), (11, 0.0, 0.6), (LAST_FRAME, 0.8, 1.2)):
    mover.location.x = x
    mover.rotation_euler = (0, 0, turn)
    mover.keyframe_insert("location", frame=frame)
    mover.keyframe_insert("rotation_euler", frame=frame)

# The camera: from the front left to the front right, looking at the room's middle.
camera_data = bpy.data.cameras.new("camera")
camera_data.lens = 24.0
camera = bpy.data.objects.new("camera", camera_data)
scene.collection.objects.link(camera)
scene.camera = camera
target = Vector((0, 0.3, 0.8))
for frame, position in ((FIRST_FRAME, (-0.7, -1.3, 1.3)), (LAST_FRAME, (0.7, -1.3, 1.3))):
    camera.location = position
    camera.rotation_euler = (target - Vector(position)).to_track_quat("-Z", "Y").to_euler()
    camera.keyframe_insert("location", frame=frame)
    camera.keyframe_insert("rotation_euler", frame=frame)

for obj in bpy.data.objects:
    if obj.animation_data and obj.animation_data.action:
        for curve in obj.animation_data.action.fcurves:
            for key in curve.keyframe_points:
                key.interpolation = "LINEAR"

bpy.ops.export_scene.gltf(
    filepath=os.path.join(OUT_DIR, "room.gltf"),
    export_format="GLTF_SEPARATE",
    export_cameras=True,
    export_lights=True,
    export_extras=True,
    export_animations=True,
    export_force_sampling=True,
    export_frame_range=True,
    export_normals=False,
    export_texcoords=False,
    export_yup=True,
)
