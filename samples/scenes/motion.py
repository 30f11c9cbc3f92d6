"""motion: motion blur (issue 17's per-sample scenes). A static camera looks at a checker floor
and a brick wall; three spheres with striped and noise textures cross the view at different
speeds (up to ~25 px over the shutter at 128 px wide) at different depths, one passing in front
of another; a tall box stays still (sharp). Motion blur on, shutter 0.5 frames, no depth of
field. Keyed motion (the Vector pass needs keys).

    blender -b --factory-startup --python-exit-code 1 --python motion.py -- --out DIR [--spp 1,4]
    (per-sample form: per_sample.py --scene motion)
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.55, 0.6, 0.7), 0.2)
    C.plane("floor", (0, 3, 0), (12, 16),
            C.checker("floor_checker", (0.75, 0.72, 0.66), (0.15, 0.17, 0.22), scale=3.0, roughness=0.5))
    C.plane("wall", (0, 6.0, 2.5), (12, 5),
            C.brick("wall_brick", (0.55, 0.3, 0.2), (0.4, 0.33, 0.28), scale=2.0, roughness=0.8),
            rotation=(math.pi / 2, 0, 0))
    C.box("pillar", (0.9, 3.2, 0.8), (0.35, 0.35, 1.6),
          C.noise_color("pillar_noise", (0.3, 0.5, 0.75), (0.9, 0.9, 0.85), scale=8.0, roughness=0.4))
    movers = [("fast_ball", (-1.6, 1.0, 0.35), 0.35, 1.6,
               C.wave_stripes("fast_stripes", (0.95, 0.9, 0.85), (0.8, 0.15, 0.1), scale=5.0)),
              ("slow_ball", (1.2, 2.6, 0.5), 0.5, -0.5,
               C.checker("slow_checker", (0.2, 0.6, 0.25), (0.9, 0.9, 0.85), scale=5.0, use_object=True)),
              ("near_ball", (0.0, -0.6, 0.22), 0.22, 0.9,
               C.noise_color("near_noise", (0.9, 0.75, 0.2), (0.3, 0.15, 0.05), scale=10.0, roughness=0.3))]
    for name, loc, radius, speed, mat in movers:
        obj = C.sphere(name, loc, radius, mat)
        obj.location.x = loc[0] - speed
        obj.keyframe_insert("location", frame=0)
        obj.location.x = loc[0] + speed
        obj.keyframe_insert("location", frame=2)
        for fc in obj.animation_data.action.fcurves:
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"
    C.area_light("key", (-2.0, -1.5, 3.5), 2.5, 350.0, color=(1.0, 0.95, 0.9))
    C.aim(bpy.data.objects["key"], (0.0, 2.0, 0.3))
    C.camera("camera", (0.0, -3.2, 1.0), (0.0, 2.0, 0.5), lens=35.0)
    scene.frame_set(1)
    return scene


def configure(scene):
    """After common.configure_render (which turns motion blur off for the flat samples)."""
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
