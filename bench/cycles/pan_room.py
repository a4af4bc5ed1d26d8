"""A Cycles shot where the camera pans over glossy and metal surfaces (issue 29).

The room of orbit_cross_room.py (its walls, box and pedestal), with a glossy
floor and a mirror-like metal sphere on it, lit by a static key light (a
sphere light of radius 20 cm: rays reflected by the metal sphere can hit it, so
the diffuse surfaces around carry caustic fireflies at a few spp; with the
6 cm light of orbit_cross_room.py those fireflies were so bright that two
512-spp references still differed by a quarter of the 4-spp input's error) and a dim
area light under the ceiling. Nothing moves but the camera, which turns about
its vertical axis by PAN_DEGREES_PER_FRAME: about 1.5 pixels a frame at 128
pixels across. In image space every pixel sees other content in every frame,
and the floor's reflections move against its texture-free surface, so a
temporal model of the pixels fails everywhere; a spatial filter of each frame
does not. Keys are CONSTANT, as in orbit_cross_room.py.

Run inside Blender (Debian 12 package, 3.4.1):
  blender -b -t 2 -P pan_room.py -- --spp 4 --seed 1 --frames 1-48 --res 128x96 --out DIR
Writes DIR/frame.####.exr (multi-layer EXR, as orbit_cross_room.py) and DIR/timing.json.
"""
import math
import os
import sys

import bpy
from mathutils import Euler

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import orbit_cross_room as room  # noqa: E402

# Horizontal field of view at 4:3 with a 58° vertical one: 72.9°, 0.57° a pixel at 128 px.
PAN_DEGREES_PER_FRAME = 0.85
PAN_START_DEGREES = -20.0  # yaw of frame 1 relative to looking at the room's back wall


def glossy(name, rgb, roughness, metallic):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes['Principled BSDF']
    bsdf.inputs['Base Color'].default_value = (*rgb, 1.0)
    bsdf.inputs['Roughness'].default_value = roughness
    bsdf.inputs['Metallic'].default_value = metallic
    bsdf.inputs['Specular'].default_value = 0.5
    return mat


def build_glossy_objects():
    floor = bpy.data.objects['floor']
    floor.data.materials[0] = glossy('glossy_floor', (0.45, 0.45, 0.47), roughness=0.12, metallic=0.0)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.35, segments=48, ring_count=24, location=(-0.15, 0.35, 0.35))
    sphere = bpy.context.active_object
    sphere.name = 'metal_sphere'
    bpy.ops.object.shade_smooth()
    sphere.data.materials.append(glossy('chrome', (0.92, 0.90, 0.86), roughness=0.03, metallic=1.0))


def build_lights():
    key_data = bpy.data.lights.new('key', 'POINT')
    key_data.energy = 150.0
    key_data.shadow_soft_size = 0.2
    key_data.color = (1.0, 0.92, 0.80)
    key = bpy.data.objects.new('key', key_data)
    bpy.context.scene.collection.objects.link(key)
    key.location = (0.9, -0.6, 2.15)
    fill_data = bpy.data.lights.new('fill', 'AREA')
    fill_data.shape = 'SQUARE'
    fill_data.size = 0.8
    fill_data.energy = 40.0
    fill_data.color = (0.75, 0.85, 1.0)
    fill = bpy.data.objects.new('fill', fill_data)
    bpy.context.scene.collection.objects.link(fill)
    fill.location = (-0.8, 1.2, room.ROOM_Z - 0.05)  # under the ceiling, facing down


def build_panning_camera(frames):
    cam = room.make_camera(1.4)
    look = cam.rotation_euler.copy()
    for f in frames:
        yaw = math.radians(PAN_START_DEGREES + PAN_DEGREES_PER_FRAME * (f - 1))
        cam.rotation_euler = Euler((look.x, look.y, look.z + yaw), look.order)
        cam.keyframe_insert('rotation_euler', frame=f)
    room.key_constant(cam)


def main():
    args = room.parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    os.makedirs(args.out, exist_ok=True)
    frames = range(min(1, args.first), max(room.SHOT_FRAMES, args.last) + 1)
    room.build_room()
    room.build_static_objects()
    build_glossy_objects()
    build_lights()
    build_panning_camera(frames)
    room.configure_render(args)
    room.render_and_time(args, 'pan_room')


if __name__ == '__main__':
    main()
