"""dof: shallow depth of field (85 mm at f/1.2, focused at about 4 m).

A noise-textured Suzanne on a pedestal is in focus; a striped ball and a brick cube in the
foreground and columns, spheres, a brick wall and small glowing bulbs (bokeh discs) in the
background are blurred, with circles of confusion up to about 12 px across at 256 px wide.
Floor is a checker, so the blur gradient along the floor is visible.

    blender -b --factory-startup --python-exit-code 1 --python dof.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

FSTOP = 1.2
LENS = 85.0


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.5, 0.55, 0.65), 0.15)

    C.plane("floor", (0, 4, 0), (12, 24),
            C.checker("floor_checker", (0.7, 0.68, 0.62), (0.18, 0.2, 0.25), scale=2.0,
                      roughness=0.45))
    C.plane("back_wall", (0, 8.0, 3.0), (12, 6),
            C.brick("wall_brick", (0.6, 0.25, 0.14), (0.45, 0.35, 0.25), scale=1.5, roughness=0.85),
            rotation=(math.pi / 2, 0, 0))

    # In-focus subject on a pedestal (planar depth ~4 m).
    ped = C.principled("pedestal", (0.8, 0.8, 0.78), roughness=0.4)
    C.cylinder("pedestal", (0, 0, 0.1), 0.22, 0.2, ped)
    subject = C.monkey("suzanne", (0, 0, 0.42), 0.45,
                       C.noise_color("suzanne_noise", (0.8, 0.2, 0.05), (0.95, 0.85, 0.3),
                                     scale=6.0, roughness=0.3, rough_variation=0.15),
                       rotation=(0, 0, math.radians(-15)))

    # Foreground (out of focus, near).
    C.sphere("fg_ball", (-0.33, -2.3, 0.15), 0.15,
             C.wave_stripes("fg_stripes", (0.95, 0.95, 0.9), (0.1, 0.2, 0.7), scale=4.0))
    C.box("fg_cube", (0.42, -1.7, 0.1), (0.2, 0.2, 0.2),
          C.brick("fg_brick", (0.85, 0.8, 0.3), (0.3, 0.5, 0.2), scale=10.0, roughness=0.5),
          rotation=(0, 0, math.radians(25)))

    # Background (out of focus, far).
    metal = C.principled("bg_metal", (0.9, 0.9, 0.92), roughness=0.15, metallic=1.0)
    C.sphere("bg_ball_1", (-0.7, 2.0, 0.3), 0.3, metal)
    C.sphere("bg_ball_2", (0.9, 4.5, 0.4), 0.4,
             C.checker("bg_checker", (0.9, 0.3, 0.3), (0.9, 0.9, 0.9), scale=6.0,
                       roughness=0.4, use_object=True))
    col = C.noise_color("column_marble", (0.85, 0.85, 0.82), (0.45, 0.45, 0.5), scale=3.0,
                        roughness=0.3)
    for i, y in enumerate((1.0, 3.0, 5.0, 7.0)):
        C.cylinder(f"column_{i}", (1.3 + 0.15 * i, y, 1.5), 0.18, 3.0, col)
        C.cylinder(f"column_l{i}", (-1.5 - 0.15 * i, y + 1.0, 1.5), 0.18, 3.0, col)
    # Small bright bulbs on the wall: bokeh discs.
    for i, (x, z, c) in enumerate([(-1.2, 0.9, (1.0, 0.7, 0.3)), (-0.4, 1.3, (0.4, 0.7, 1.0)),
                                   (0.5, 1.0, (1.0, 0.5, 0.5)), (1.1, 1.5, (0.9, 0.9, 0.6)),
                                   (0.0, 0.6, (0.6, 1.0, 0.6))]):
        C.sphere(f"bulb_{i}", (x, 7.95, z), 0.03, C.emitter(f"bulb_{i}", c, 60.0),
                 segments=16, rings=8)

    C.area_light("key", (-2.5, -2.0, 3.5), 2.0, 300.0, color=(1.0, 0.95, 0.88))
    C.aim(bpy.data.objects["key"], (0.0, 1.0, 0.3))
    C.area_light("fill", (3.0, 3.0, 3.0), 3.0, 180.0, color=(0.8, 0.88, 1.0))
    C.aim(bpy.data.objects["fill"], (0.0, 3.0, 0.5))

    cam = C.camera("camera", (0.0, -4.0, 0.45), (0.0, 0.0, 0.3), lens=LENS)
    d = cam.data.dof
    d.use_dof = True
    d.aperture_fstop = FSTOP
    d.aperture_blades = 0
    # Focus distance is planar (along the view axis): put the focus plane on the subject.
    bpy.context.view_layer.update()
    fwd = cam.matrix_world.to_3x3() @ Vector((0, 0, -1))
    d.focus_distance = (subject.location - cam.location).dot(fwd)
    return scene


if __name__ == "__main__":
    args = C.parse_args("dof", default_size=(256, 192))
    build()
    C.render_jobs(args, "dof")
