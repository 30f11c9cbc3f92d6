"""cutout: studio's objects as a cut-out on a transparent background, for compositing.

Held out: never used to choose settings (the artist's set-up no other sample has: hair and
translucent leaves over Film > Transparent, with no floor or wall behind them, so the fur's
fringe, the leaves' edges and the flame are all partial coverage against alpha 0). The objects,
materials and lights of `studio` (a furry ball of particle hair far thinner than a pixel, a
subsurface wax candle and its flame, a screen showing an emissive picture, two back-lit leaves);
its table and back wall are not rendered. With no shadow catcher the alpha is the mean of the
samples, so the 16-spp level also comes as two half buffers.

    blender -b --factory-startup --python-exit-code 1 --python cutout.py -- --out DIR [--spp 1,4]
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402
import studio  # noqa: E402


def build():
    import bpy
    scene = studio.build()
    for name in ("table", "back_wall"):
        bpy.data.objects[name].hide_render = True
    return scene


if __name__ == "__main__":
    args = C.parse_args("cutout", default_size=(256, 192))
    build()
    # One BVH for the process, as studio (its hair BVH is not built alike twice).
    C.render_jobs(args, "cutout", persistent=True, transparent=True)
