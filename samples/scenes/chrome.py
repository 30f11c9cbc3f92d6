"""chrome: 16-frame dolly past chrome on a kitchen counter under one small, strong lamp.

Held-out ("report") companion of `metal`, of the same class (polished metal mirroring a small
strong light, indirect clamp off) but different content and construction: an indoor corner
instead of an open set, a point lamp instead of a sun, cylinders and a bevelled box instead of
a sphere, and a straight two-key dolly instead of an orbit.

A kitchen corner: glossy square tiles (dielectric, roughness 0.1, stacked Brick texture) on the
back and left walls, a wooden counter (wave texture) on a painted cabinet. On the counter: a
chrome tap (cylinders, an elbow sphere; metallic, roughness 0.04) behind a brushed-steel tray
(metallic, roughness 0.25, anisotropic), a chrome kettle (squashed sphere, torus handle,
cylinder spout; roughness 0.03), a chrome toaster (bevelled box, roughness 0.06), a glass
tumbler and a red ceramic mug. Lit by one point lamp of 2.5 cm radius and high power, up and to
the right in front of the counter (out of view: its mirror images on the chrome are a few
pixels, very bright), plus a dim grey world through the open sides.

The camera dollies 0.75 m to the left and 0.2 m closer while panning the same way: two keys
(frames 1 and 16), linear interpolation and extrapolation, so every frame has motion vectors
both ways and the lamp's highlights slide along the tap, kettle and toaster.

The noisy frames carry Blender's light passes (as `metal`'s: the held-out check of
components=light_passes), besides the usual passes; the references are Combined only. Indirect
clamp off.

    blender -b --factory-startup --python-exit-code 1 --python chrome.py -- --out DIR [--frames 1-16]
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

CLAMP_INDIRECT = 0.0  # off: a production render keeps its fireflies
FRAMES = (1, 16)
COUNTER_Z = 0.9  # top of the counter
R90 = math.pi / 2
# (location, aim point) of the camera at the first and the last frame.
CAM_KEYS = (((0.75, -1.1, 1.42), (0.3, 0.45, 0.98)), ((-0.3, -0.85, 1.36), (-0.1, 0.45, 0.98)))


def tiles(name, tile=0.1):
    """Glossy square wall tiles: a Brick texture with no row offset and square bricks (UVs of
    C.plane are in metres), two slightly different glazes and grey grout."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    bsdf = nt.nodes.get("Principled BSDF")
    tex = nt.nodes.new("ShaderNodeTexBrick")
    tex.offset = 0.0
    tex.inputs["Color1"].default_value = (0.86, 0.88, 0.88, 1.0)
    tex.inputs["Color2"].default_value = (0.62, 0.74, 0.78, 1.0)
    tex.inputs["Mortar"].default_value = (0.30, 0.29, 0.27, 1.0)
    tex.inputs["Scale"].default_value = 1.0
    tex.inputs["Brick Width"].default_value = tile
    tex.inputs["Row Height"].default_value = tile
    tex.inputs["Mortar Size"].default_value = 0.004
    tex.inputs["Bias"].default_value = 0.0
    uv = nt.nodes.new("ShaderNodeTexCoord")
    nt.links.new(uv.outputs["UV"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.1
    bsdf.inputs["Specular"].default_value = 0.5
    return mat


def bevel(obj, width, segments=5):
    """Rounded edges with smooth normals across the bevel and sharp flat faces."""
    mod = obj.modifiers.new("Bevel", "BEVEL")
    mod.width = width
    mod.segments = segments
    obj.data.use_auto_smooth = True
    obj.data.auto_smooth_angle = math.radians(30.0)
    for poly in obj.data.polygons:
        poly.use_smooth = True
    return obj


def build_room():
    C.plane("floor", (0.3, -0.5, 0.0), (3.0, 2.4),
            C.principled("floor_slate", (0.12, 0.12, 0.13), roughness=0.6))
    wall_tiles = tiles("wall_tiles")
    C.plane("wall_back", (0.3, 0.65, 1.4), (2.6, 2.8), wall_tiles, rotation=(R90, 0, 0))
    C.plane("wall_left", (-1.0, -0.2, 1.4), (2.8, 1.7), wall_tiles, rotation=(0, R90, 0))
    C.box("counter_top", (0.3, 0.32, COUNTER_Z - 0.02), (2.6, 0.7, 0.04),
          C.wave_stripes("oak", (0.62, 0.42, 0.22), (0.38, 0.22, 0.10), scale=7.0,
                         roughness=0.35))
    C.box("cabinet", (0.3, 0.35, (COUNTER_Z - 0.04) / 2), (2.6, 0.6, COUNTER_Z - 0.04),
          C.principled("cabinet_paint", (0.32, 0.42, 0.38), roughness=0.45))


def build_props():
    z0 = COUNTER_Z
    chrome = C.principled("chrome", (0.95, 0.95, 0.96), roughness=0.04, metallic=1.0)
    steel = C.principled("brushed_steel", (0.62, 0.63, 0.65), roughness=0.25, metallic=1.0)
    steel.node_tree.nodes.get("Principled BSDF").inputs["Anisotropic"].default_value = 0.6

    # Brushed-steel tray (sink): a base plate and four rims.
    tx, ty, tw, td, th = 0.25, 0.28, 0.56, 0.36, 0.05
    C.box("tray_base", (tx, ty, z0 + 0.006), (tw, td, 0.012), steel)
    for i, (cx, cy, sx, sy) in enumerate([(tx, ty - td / 2, tw, 0.012), (tx, ty + td / 2, tw, 0.012),
                                          (tx - tw / 2, ty, 0.012, td), (tx + tw / 2, ty, 0.012, td)]):
        C.box(f"tray_rim_{i}", (cx, cy, z0 + th / 2), (sx, sy, th), steel)

    # Chrome tap behind the tray: base, riser, elbow, spout towards the camera, nozzle, lever.
    ax, ay, top = 0.25, 0.56, z0 + 0.32
    C.cylinder("tap_base", (ax, ay, z0 + 0.015), 0.036, 0.03, chrome)
    C.cylinder("tap_riser", (ax, ay, (z0 + 0.03 + top) / 2), 0.021, top - z0 - 0.03, chrome)
    C.sphere("tap_elbow", (ax, ay, top), 0.021, chrome, segments=48, rings=24)
    C.cylinder("tap_spout", (ax, ay - 0.11, top), 0.018, 0.22, chrome, rotation=(R90, 0, 0))
    C.cylinder("tap_nozzle", (ax, ay - 0.21, top - 0.03), 0.016, 0.06, chrome)
    C.cylinder("tap_lever", (ax + 0.06, ay, z0 + 0.16), 0.009, 0.1, chrome,
               rotation=(0, R90, math.radians(-20)))

    # Chrome kettle on the left: squashed sphere body, lid, knob, torus handle, spout.
    kx, ky = -0.45, 0.36
    body = C.sphere("kettle_body", (kx, ky, z0 + 0.1), 0.13, chrome)
    body.scale = (1.0, 1.0, 0.78)
    C.cylinder("kettle_lid", (kx, ky, z0 + 0.2), 0.06, 0.02, chrome)
    C.sphere("kettle_knob", (kx, ky, z0 + 0.225), 0.018, chrome, segments=32, rings=16)
    C.torus("kettle_handle", (kx, ky, z0 + 0.2), 0.09, 0.012, chrome, rotation=(R90, 0, 0))
    C.cylinder("kettle_spout", (kx + 0.15, ky - 0.03, z0 + 0.13), 0.016, 0.14, chrome,
               rotation=(0, math.radians(50), math.radians(-12)))

    # Chrome toaster on the right: a bevelled box with two slots' worth of dark top strips.
    toaster = C.box("toaster", (1.05, 0.42, z0 + 0.095), (0.3, 0.17, 0.19),
                    C.principled("chrome_satin", (0.93, 0.93, 0.94), roughness=0.06,
                                 metallic=1.0), rotation=(0, 0, math.radians(-12)))
    bevel(toaster, 0.03)
    dark = C.principled("slot_black", (0.02, 0.02, 0.02), roughness=0.5)
    for i, dy in enumerate((-0.03, 0.03)):
        C.box(f"toaster_slot_{i}", (1.05 - dy * math.sin(math.radians(12)),
                                    0.42 + dy * math.cos(math.radians(12)), z0 + 0.19),
              (0.22, 0.018, 0.004), dark, rotation=(0, 0, math.radians(-12)))

    # Glass tumbler (front right) and a red ceramic mug with a handle (front left).
    C.cylinder("tumbler", (0.72, 0.16, z0 + 0.055), 0.038, 0.11, C.glass("clear_glass", color=(0.95, 0.98, 0.97)))
    mug = C.principled("red_glaze", (0.55, 0.06, 0.05), roughness=0.15)
    C.cylinder("mug", (-0.12, 0.12, z0 + 0.045), 0.04, 0.09, mug)
    C.torus("mug_handle", (-0.12 + 0.045, 0.12, z0 + 0.05), 0.025, 0.007, mug,
            rotation=(R90, 0, 0))


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.75, 0.78, 0.82), 0.12)
    build_room()
    build_props()
    # The small strong lamp: up and to the right, in front of the counter, out of view.
    C.point_light("lamp", (1.0, -0.45, 1.85), 0.025, 70.0, color=(1.0, 0.92, 0.8))

    # Camera: two keys, a straight dolly left and in while panning the same way.
    cam = C.camera("camera", CAM_KEYS[0][0], CAM_KEYS[0][1], lens=26.0)
    for frame, (loc, target) in zip(FRAMES, CAM_KEYS):
        cam.location = loc
        C.aim(cam, target)
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    C.linear_keys(cam)
    scene.frame_start, scene.frame_end = FRAMES
    scene.render.fps = 24
    return scene


if __name__ == "__main__":
    args = C.parse_args("chrome", default_size=(192, 108), sequence=True)
    build()
    C.render_jobs(args, "chrome", clamp_indirect=CLAMP_INDIRECT, light_passes=True)
