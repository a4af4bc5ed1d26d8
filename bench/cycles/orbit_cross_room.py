"""A Cycles shot that breaks a temporal low-rank model (issue 29 item 5).

A closed Lambertian room seen by a static camera. Three things change over time:
  * the key light (a small point light) orbits the room under the ceiling, one
    turn in 48 frames, so every shadow sweeps across floor and walls;
  * a small sphere flies across the room in frames 20-29 only, with its shadow;
  * a second light (an area light) switches on at frame 33 and stays on.
Every animated value is keyed on every frame with CONSTANT interpolation, so a
frame's content depends only on its number (a subset of frames renders the same).

Run inside Blender (Debian 12 package, 3.4.1):
  blender -b -t 2 -P orbit_cross_room.py -- --spp 4 --seed 1 --frames 1-48 \
      --res 128x96 --out DIR
--without-crosser renders the same frames with the sphere hidden throughout.
Writes DIR/frame.####.exr (multi-layer EXR, colour passes half, layer prefix
"ViewLayer.") and DIR/timing.json (seconds per frame: scene sync + path tracing).
"""
import argparse
import json
import math
import os
import sys
import time

import bpy
from mathutils import Vector

SHOT_FRAMES = 48  # the orbit period and the shot's nominal length

# Room: x in [-ROOM_X, ROOM_X], y in [-ROOM_Y, ROOM_Y], z in [0, ROOM_Z] (metres, Z up).
ROOM_X, ROOM_Y, ROOM_Z = 2.0, 2.6, 2.5

# Key light orbit: a circle of ORBIT_R around the room's vertical axis at ORBIT_Z.
ORBIT_R, ORBIT_Z = 1.3, 2.2

# Crossing sphere: flies along y = CROSS_Y, z = CROSS_Z from x = -CROSS_X to +CROSS_X.
CROSS_FIRST, CROSS_LAST = 20, 29
CROSS_X, CROSS_Y, CROSS_Z, CROSS_RADIUS = 1.6, -0.2, 0.45, 0.11

SWITCH_FRAME = 33  # the second light is off before, on from here


def parse_args():
    argv = sys.argv[sys.argv.index('--') + 1:] if '--' in sys.argv else []
    parser = argparse.ArgumentParser(prog='orbit_cross_room.py')
    parser.add_argument('--spp', type=int, required=True)
    parser.add_argument('--seed', type=int, required=True)
    parser.add_argument('--frames', default=f'1-{SHOT_FRAMES}', help='FIRST-LAST')
    parser.add_argument('--res', default='128x96', help='WIDTHxHEIGHT')
    parser.add_argument('--out', required=True, help='output directory')
    parser.add_argument('--fixed-seed', action='store_true',
                        help='the same random numbers in every frame (Cycles\' default: animated seed off)')
    parser.add_argument('--without-crosser', action='store_true',
                        help='hide the crossing sphere in every frame (to find its region and shadow)')
    args = parser.parse_args(argv)
    args.first, args.last = (int(v) for v in args.frames.split('-'))
    args.width, args.height = (int(v) for v in args.res.lower().split('x'))
    if args.first < 1 or args.last < args.first or args.spp < 1:
        parser.error(f'bad --frames {args.frames} or --spp {args.spp}')
    return args


def diffuse(name, rgb):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    bsdf = nodes.new('ShaderNodeBsdfDiffuse')
    bsdf.inputs['Color'].default_value = (*rgb, 1.0)
    bsdf.inputs['Roughness'].default_value = 0.0
    out = nodes.new('ShaderNodeOutputMaterial')
    links.new(bsdf.outputs['BSDF'], out.inputs['Surface'])
    return mat


def quad(name, corners, inward, mat):
    """One planar quad whose normal points along `inward` (into the room)."""
    v = [Vector(c) for c in corners]
    if (v[1] - v[0]).cross(v[2] - v[0]).dot(Vector(inward)) < 0:
        v.reverse()
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(p) for p in v], [], [(0, 1, 2, 3)])
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def build_room():
    x, y, z = ROOM_X, ROOM_Y, ROOM_Z
    grey = diffuse('warm_grey', (0.60, 0.57, 0.52))
    quad('floor', [(-x, -y, 0), (x, -y, 0), (x, y, 0), (-x, y, 0)], (0, 0, 1), diffuse('floor', (0.70, 0.70, 0.70)))
    quad('ceiling', [(-x, -y, z), (x, -y, z), (x, y, z), (-x, y, z)], (0, 0, -1), diffuse('ceiling', (0.75, 0.75, 0.75)))
    quad('wall_left', [(-x, -y, 0), (-x, y, 0), (-x, y, z), (-x, -y, z)], (1, 0, 0), diffuse('red', (0.62, 0.12, 0.10)))
    quad('wall_right', [(x, -y, 0), (x, y, 0), (x, y, z), (x, -y, z)], (-1, 0, 0), diffuse('green', (0.15, 0.50, 0.18)))
    quad('wall_back', [(-x, y, 0), (x, y, 0), (x, y, z), (-x, y, z)], (0, -1, 0), grey)
    quad('wall_front', [(-x, -y, 0), (x, -y, 0), (x, -y, z), (-x, -y, z)], (0, 1, 0), grey)


def build_static_objects():
    white = diffuse('white', (0.78, 0.78, 0.78))
    bpy.ops.mesh.primitive_cylinder_add(vertices=48, radius=0.32, depth=0.7, location=(0.75, 0.7, 0.35))
    pedestal = bpy.context.active_object
    pedestal.name = 'pedestal'
    pedestal.data.materials.append(white)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.75, 0.7, 0.85))  # a block on the pedestal
    block = bpy.context.active_object
    block.name = 'block'
    block.scale = (0.25, 0.25, 0.3)
    block.rotation_euler = (0, 0, math.radians(30))
    block.data.materials.append(diffuse('blue', (0.15, 0.25, 0.65)))
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-1.0, 1.0, 0.3))
    box = bpy.context.active_object
    box.name = 'box'
    box.scale = (0.7, 0.55, 0.6)
    box.rotation_euler = (0, 0, math.radians(-20))
    box.data.materials.append(diffuse('tan', (0.72, 0.55, 0.35)))


def key_constant(id_data):
    """Every keyframe of id_data holds its value until the next one."""
    for fcurve in id_data.animation_data.action.fcurves:
        for point in fcurve.keyframe_points:
            point.interpolation = 'CONSTANT'


def build_lights(frames):
    key_data = bpy.data.lights.new('key', 'POINT')
    key_data.energy = 150.0
    key_data.shadow_soft_size = 0.06
    key_data.color = (1.0, 0.92, 0.80)
    key = bpy.data.objects.new('key', key_data)
    bpy.context.scene.collection.objects.link(key)
    key.visible_camera = False
    for f in frames:
        angle = 2 * math.pi * (f - 1) / SHOT_FRAMES
        key.location = (ORBIT_R * math.cos(angle), ORBIT_R * math.sin(angle), ORBIT_Z)
        key.keyframe_insert('location', frame=f)
    key_constant(key)

    fill_data = bpy.data.lights.new('switch', 'AREA')
    fill_data.shape = 'SQUARE'
    fill_data.size = 0.4
    fill_data.color = (0.70, 0.82, 1.0)
    fill = bpy.data.objects.new('switch', fill_data)
    bpy.context.scene.collection.objects.link(fill)
    fill.visible_camera = False
    fill.location = (-1.2, 2.45, 1.7)  # near the back wall, aimed into the room and down
    fill.rotation_euler = (math.radians(-60), 0, math.radians(-25))
    for f in frames:
        fill_data.energy = 80.0 if f >= SWITCH_FRAME else 0.0
        fill_data.keyframe_insert('energy', frame=f)
    key_constant(fill_data)


def build_crossing_sphere(frames, hidden):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=CROSS_RADIUS, segments=32, ring_count=16)
    sphere = bpy.context.active_object
    sphere.name = 'crosser'
    bpy.ops.object.shade_smooth()
    sphere.data.materials.append(diffuse('yellow', (0.85, 0.70, 0.15)))
    span = CROSS_LAST - CROSS_FIRST
    for f in frames:
        present = CROSS_FIRST <= f <= CROSS_LAST
        t = (f - CROSS_FIRST) / span if present else 0.0
        sphere.location = (-CROSS_X + 2 * CROSS_X * t, CROSS_Y, CROSS_Z)
        sphere.hide_render = hidden or not present
        sphere.keyframe_insert('location', frame=f)
        sphere.keyframe_insert('hide_render', frame=f)
    key_constant(sphere)


def make_camera(height):
    """The scene's camera near the front wall at `height`, looking into the room."""
    cam_data = bpy.data.cameras.new('camera')
    cam_data.sensor_fit = 'VERTICAL'
    cam_data.angle_y = math.radians(58)
    cam = bpy.data.objects.new('camera', cam_data)
    bpy.context.scene.collection.objects.link(cam)
    cam.location = (0.0, -2.35, height)
    cam.rotation_euler = (Vector((0.0, 0.9, 0.55)) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    bpy.context.scene.camera = cam
    return cam


def configure_render(args):
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.world = bpy.data.worlds.new('black')
    scene.world.color = (0, 0, 0)
    cycles = scene.cycles
    cycles.device = 'CPU'
    cycles.samples = args.spp
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = args.seed
    cycles.use_animated_seed = not args.fixed_seed
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.max_bounces = 8
    cycles.diffuse_bounces = 4
    cycles.glossy_bounces = 4
    scene.render.threads_mode = 'FIXED'
    scene.render.threads = 2
    scene.render.use_motion_blur = False
    scene.render.use_persistent_data = False
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.height
    scene.render.resolution_percentage = 100
    scene.frame_start, scene.frame_end = args.first, args.last

    layer = scene.view_layers[0]
    layer.name = 'ViewLayer'
    for attr in ('use_pass_combined', 'use_pass_z', 'use_pass_normal', 'use_pass_diffuse_direct',
                 'use_pass_diffuse_indirect', 'use_pass_diffuse_color', 'use_pass_glossy_direct',
                 'use_pass_glossy_indirect', 'use_pass_glossy_color'):
        setattr(layer, attr, True)
    layer.cycles.denoising_store_passes = True  # Denoising Albedo / Normal, without denoising

    image = scene.render.image_settings
    image.file_format = 'OPEN_EXR_MULTILAYER'
    image.color_depth = '16'
    image.exr_codec = 'ZIP'
    scene.render.use_file_extension = True
    scene.render.filepath = os.path.join(os.path.abspath(args.out), 'frame.####')


def main():
    args = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    os.makedirs(args.out, exist_ok=True)
    # Keys cover the whole shot and any frames asked beyond it.
    frames = range(min(1, args.first), max(SHOT_FRAMES, args.last) + 1)
    build_room()
    build_static_objects()
    build_lights(frames)
    build_crossing_sphere(frames, args.without_crosser)
    make_camera(1.5)
    configure_render(args)
    render_and_time(args, 'orbit_cross_room')


def render_and_time(args, shot):
    """Renders the animation as configured and writes OUT/timing.json (seconds per
    frame: scene sync + path tracing)."""
    times, start = {}, {}
    bpy.app.handlers.render_pre.append(lambda scene, *_: start.__setitem__('t', time.time()))
    bpy.app.handlers.render_post.append(
        lambda scene, *_: times.__setitem__(scene.frame_current, time.time() - start['t']))
    begin = time.time()
    bpy.ops.render.render(animation=True)
    total = time.time() - begin
    with open(os.path.join(args.out, 'timing.json'), 'w') as f:
        json.dump({'spp': args.spp, 'seed': args.seed, 'fixed_seed': args.fixed_seed, 'res': args.res,
                   'frames': args.frames,
                   'per_frame_s': {str(k): round(v, 3) for k, v in sorted(times.items())},
                   'total_render_call_s': round(total, 2)}, f, indent=1)
    print(f'{shot}: {len(times)} frames, {total:.1f} s')


if __name__ == '__main__':  # pan_room.py imports the room and the render settings
    main()
