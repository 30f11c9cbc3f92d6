"""anim: 16-frame camera move through a textured room (keyframed, so the Vector pass is set).

A brick/plaster room with a checker floor, a table with a noise-textured Suzanne, a shelf of
coloured boxes, metal and striped spheres and a spinning brick cube. The camera trucks sideways
8 cm per frame while panning slightly the same way (parallax: a few pixels per frame,
more in the foreground); the cube spins 6 degrees per frame. All motion is keyframed with linear
interpolation and linear extrapolation, so every frame, including the first and the last, has
non-zero motion vectors in both directions.

    blender -b --factory-startup --python-exit-code 1 --python anim.py -- --out DIR [--frames 1-16]
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

W, D, H = 5.0, 6.0, 2.8
FRAMES = (1, 16)



def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.0, 0.0, 0.0), 0.0)
    r90 = math.pi / 2

    plaster = C.noise_color("plaster", (0.72, 0.70, 0.64), (0.60, 0.62, 0.66), scale=2.0,
                            roughness=0.9)
    C.plane("floor", (0, 0, 0), (W, D),
            C.checker("floor_checker", (0.55, 0.42, 0.30), (0.30, 0.22, 0.16), scale=2.5,
                      roughness=0.3))
    C.plane("ceiling", (0, 0, H), (W, D), C.principled("ceiling", (0.8, 0.8, 0.8), roughness=0.9),
            rotation=(math.pi, 0, 0))
    C.plane("wall_back", (0, D / 2, H / 2), (W, H),
            C.brick("brick", (0.55, 0.22, 0.13), (0.40, 0.30, 0.22), scale=3.0, roughness=0.85),
            rotation=(r90, 0, 0))
    C.plane("wall_front", (0, -D / 2, H / 2), (W, H), plaster, rotation=(-r90, 0, 0))
    C.plane("wall_left", (-W / 2, 0, H / 2), (H, D), plaster, rotation=(0, r90, 0))
    C.plane("wall_right", (W / 2, 0, H / 2), (H, D),
            C.principled("wall_teal", (0.15, 0.42, 0.45), roughness=0.8), rotation=(0, -r90, 0))

    # Table with a Suzanne and a copper ring.
    wood = C.wave_stripes("wood", (0.55, 0.33, 0.15), (0.32, 0.17, 0.07), scale=4.0,
                          roughness=0.35)
    C.box("table_top", (0.0, 1.0, 0.75), (1.4, 0.8, 0.05), wood)
    for i, (x, y) in enumerate([(-0.62, 0.68), (0.62, 0.68), (-0.62, 1.32), (0.62, 1.32)]):
        C.box(f"table_leg_{i}", (x, y, 0.3625), (0.05, 0.05, 0.725), wood)
    C.monkey("suzanne", (-0.2, 1.0, 1.0), 0.5,
             C.noise_color("suzanne_noise", (0.1, 0.3, 0.7), (0.9, 0.8, 0.25), scale=5.0,
                           roughness=0.3, rough_variation=0.15),
             rotation=(math.radians(-5), 0, math.radians(-20)))
    C.torus("bowl", (0.4, 0.95, 0.8), 0.16, 0.045,
            C.principled("copper", (0.95, 0.6, 0.45), roughness=0.2, metallic=1.0))

    # Shelf with coloured boxes against the back wall, right side.
    shelf = C.principled("shelf", (0.85, 0.85, 0.82), roughness=0.6)
    for k, z in enumerate((0.4, 0.9, 1.4)):
        C.box(f"shelf_{k}", (1.5, 2.8, z), (1.2, 0.35, 0.03), shelf)
    colours = [(0.7, 0.1, 0.1), (0.1, 0.3, 0.7), (0.8, 0.6, 0.1), (0.2, 0.55, 0.2),
               (0.6, 0.6, 0.6), (0.5, 0.2, 0.5)]
    for k in range(9):
        x = 1.05 + 0.12 * (k % 8)
        z = (0.4, 0.9, 1.4)[k % 3] + 0.015
        h = 0.18 + 0.05 * ((k * 7) % 4)
        C.box(f"book_{k}", (x, 2.8, z + h / 2), (0.08, 0.25, h),
              C.principled(f"book_{k}", colours[k % len(colours)], roughness=0.5))

    # Floor objects: metal sphere, striped sphere, spinning brick cube.
    C.sphere("metal_ball", (-1.2, 0.3, 0.3), 0.3,
             C.principled("chrome", (0.9, 0.9, 0.9), roughness=0.08, metallic=1.0))
    C.sphere("striped_ball", (1.1, 0.0, 0.22), 0.22,
             C.wave_stripes("ball_stripes", (0.95, 0.9, 0.85), (0.7, 0.15, 0.1), scale=3.0))
    cube = C.box("spin_cube", (0.5, -0.15, 0.2), (0.3, 0.3, 0.3),
                 C.brick("cube_brick", (0.8, 0.75, 0.4), (0.3, 0.45, 0.6), scale=8.0,
                         roughness=0.5))
    cube.rotation_euler = (0, 0, 0)
    cube.keyframe_insert("rotation_euler", frame=FRAMES[0])
    cube.rotation_euler = (0, 0, math.radians(6.0 * (FRAMES[1] - FRAMES[0])))
    cube.keyframe_insert("rotation_euler", frame=FRAMES[1])
    C.linear_keys(cube)

    # Lights: soft ceiling panel (visible) and a window-like emitter on the left wall.
    C.area_light("ceiling_lamp", (0.0, -0.4, H - 0.02), 1.2, 170.0, color=(1.0, 0.93, 0.82),
                 size_y=0.6)
    C.plane("window", (-W / 2 + 0.01, 0.8, 1.6), (0.9, 1.1),
            C.emitter("window_light", (0.75, 0.85, 1.0), 3.5), rotation=(0, r90, 0))

    # Camera: truck +x with a slight pan the same way (no compensation), keyframed.
    cam = C.camera("camera", (-0.6, -2.2, 1.35), (-0.6, 1.0, 0.8), lens=30.0)
    start_loc, start_rot = cam.location.copy(), cam.rotation_euler.copy()
    cam.keyframe_insert("location", frame=FRAMES[0])
    cam.keyframe_insert("rotation_euler", frame=FRAMES[0])
    cam.location = (0.6, -2.0, 1.30)
    C.aim(cam, (0.9, 1.0, 0.8))
    cam.keyframe_insert("location", frame=FRAMES[1])
    cam.keyframe_insert("rotation_euler", frame=FRAMES[1])
    C.linear_keys(cam)
    scene.frame_start, scene.frame_end = FRAMES
    scene.render.fps = 24
    return scene


if __name__ == "__main__":
    args = C.parse_args("anim", default_size=(320, 180), sequence=True)
    build()
    C.render_jobs(args, "anim")
