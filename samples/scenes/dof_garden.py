"""dof_garden: a second depth-of-field scene, held out (issue 17: never used to choose a setting;
the sweep's figures on it are reported as they come). A row of coloured posts and rings recedes
from the camera along a path of tiles; a noise-textured bush on the right, a striped ball near
the lens; 50 mm at f/1.8 focused on the fourth post (~3.5 m).

    (per-sample form) per_sample.py --scene dof_garden
"""
import math
import os
import sys

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def build():
    scene = C.reset_scene()
    C.sky_world(scene, 35.0, 40.0, strength=0.12)
    C.plane("ground", (0, 5, 0), (14, 20),
            C.checker("tiles", (0.55, 0.5, 0.42), (0.3, 0.28, 0.25), scale=5.0, roughness=0.6))
    colours = [(0.8, 0.15, 0.1), (0.9, 0.7, 0.1), (0.15, 0.6, 0.2), (0.1, 0.35, 0.8), (0.6, 0.2, 0.7),
               (0.9, 0.9, 0.85), (0.2, 0.2, 0.2)]
    posts = []
    for i, c in enumerate(colours):
        y = 0.8 + 0.9 * i
        x = -0.5 + 0.25 * (i % 2)
        posts.append(C.cylinder(f"post_{i}", (x, y, 0.45), 0.08, 0.9,
                                C.principled(f"post_{i}", c, roughness=0.35)))
        C.torus(f"ring_{i}", (x + 0.45, y, 0.25), 0.18, 0.04, C.principled(f"ring_{i}", c[::-1], roughness=0.2,
                                                                           metallic=0.6),
                rotation=(math.radians(90), 0, math.radians(20 * i)))
    C.sphere("bush", (1.0, 2.8, 0.4), 0.45,
             C.noise_color("leaves", (0.1, 0.35, 0.08), (0.35, 0.55, 0.15), scale=14.0, roughness=0.6))
    C.sphere("near_ball", (0.25, -0.9, 0.3), 0.12,
             C.wave_stripes("near_stripes", (0.95, 0.95, 0.95), (0.2, 0.1, 0.6), scale=6.0))
    C.sun_light("sun", (math.radians(50), 0, math.radians(30)), 1.2, angle_deg=2.0)
    cam = C.camera("camera", (0.35, -2.2, 0.75), (-0.2, 4.0, 0.3), lens=50.0)
    d = cam.data.dof
    d.use_dof = True
    d.aperture_fstop = 1.8
    bpy.context.view_layer.update()
    fwd = cam.matrix_world.to_3x3() @ Vector((0, 0, -1))
    d.focus_distance = (posts[3].location - cam.location).dot(fwd)
    return scene
