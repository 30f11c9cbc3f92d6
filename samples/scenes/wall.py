"""wall: a flat textured wall filling the frame, straight on ("constant normal, no depth of field").

An orthographic camera looks straight at a plastered brick wall much larger than its view, so
every pixel sees the same plane: the Normal and Denoising Normal passes are constant over the
frame (and, orthographic, so are Depth and Denoising Depth); only Position varies. Light comes
from a large area light at a grazing angle from the left (a brightness gradient across the
frame) plus a dim grey world; a pole outside the view casts a soft shadow across the wall.
No depth of field, no motion.

    blender -b --factory-startup --python-exit-code 1 --python wall.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

VIEW_W = 4.0  # metres of wall across the frame (orthographic scale)


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.55, 0.55, 0.58), 0.12)

    # Wall in the plane y = 0, facing -y (towards the camera); 12 x 8 m, the view is 4 x 3 m.
    plaster = C.brick("plastered_brick", (0.74, 0.70, 0.64), (0.60, 0.52, 0.45),
                      mortar=(0.86, 0.85, 0.82), scale=2.2, roughness=0.9)
    C.plane("wall", (0, 0, 0), (12, 8), plaster, rotation=(math.pi / 2, 0, 0))
    # Floor below the view, for a little bounce light.
    C.plane("floor", (0, -3, -2.5), (12, 6), C.principled("floor", (0.4, 0.38, 0.35),
                                                           roughness=0.8))

    # Grazing light from the left, 1.2 m in front of the wall.
    key = C.area_light("grazing_key", (-7.0, -1.2, 0.6), 0.7, 3000.0, color=(1.0, 0.92, 0.8))
    C.aim(key, (0.0, -0.2, 0.0))
    # Pole outside the view (x = -3.5) between the light and the wall: a soft vertical shadow
    # around x = -1.
    C.cylinder("pole", (-3.5, -0.5, 0.0), 0.1, 8.0, C.principled("pole", (0.2, 0.2, 0.2)))

    C.camera("camera", (0.0, -6.0, 0.0), (0.0, 0.0, 0.0), ortho_scale=VIEW_W)
    return scene


if __name__ == "__main__":
    args = C.parse_args("wall", default_size=(256, 192))
    build()
    C.render_jobs(args, "wall")
