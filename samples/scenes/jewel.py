"""jewel: polished metal and cut glass under a sun, on a transparent background with a shadow catcher.

A tune scene (settings may be chosen on it) of the class "sub-pixel highlights dominate the
error": the frame holds little else to filter (Film > Transparent, the floor a shadow catcher),
so at 64 spp the mirror images of a small sun on polished metal, a few pixels each and very
bright, are what relMSE sees. Built after the glossy-on-transparent variants of session 29 showed
every feature filter worse than its input at 64 spp there; different content: a silver sphere
(roughness 0.02), a gold ring standing up (0.05), five chrome bearing balls in a row (radius
1.5 cm: a highlight smaller than a pixel on each), a faceted glass prism (an 8-sided cylinder,
flat shaded), a brushed-steel spoon bowl (a squashed sphere, 0.2) and a matte blue cube. Lit by
a Sun lamp (0.5 degree disc) from the upper right, a small strong area light from the left and
a procedural sky that only the metal and glass show.

    blender -b --factory-startup --python-exit-code 1 --python jewel.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def build():
    scene = C.reset_scene()
    C.sky_world(scene, 40.0, 200.0, strength=0.2)

    catcher = C.plane("catcher", (0, 1.0, 0), (10, 10), C.principled("catcher", (0.8, 0.8, 0.8), 0.5))
    catcher.is_shadow_catcher = True

    C.sphere("silver", (-0.55, 1.3, 0.28), 0.28,
             C.principled("silver", (0.95, 0.95, 0.96), roughness=0.02, metallic=1.0))
    C.torus("gold_ring", (0.15, 1.55, 0.25), 0.2, 0.05,
            C.principled("gold", (1.0, 0.77, 0.34), roughness=0.05, metallic=1.0),
            rotation=(math.radians(90), 0, math.radians(20)))
    chrome = C.principled("chrome", (0.9, 0.9, 0.92), roughness=0.03, metallic=1.0)
    for i in range(5):
        C.sphere(f"ball_{i}", (-0.5 + 0.16 * i, 0.55, 0.015), 0.015, chrome, segments=24, rings=12)
    prism = C.cylinder("prism", (0.65, 1.0, 0.2), 0.14, 0.4, C.glass("prism_glass", ior=1.6), vertices=8)
    for poly in prism.data.polygons:
        poly.use_smooth = False
    bowl = C.sphere("spoon_bowl", (0.05, 0.8, 0.04), 0.16,
                    C.principled("brushed", (0.78, 0.78, 0.8), roughness=0.2, metallic=1.0))
    bowl.scale = (1.0, 0.6, 0.25)
    C.box("blue_cube", (-0.15, 1.9, 0.15), (0.3, 0.3, 0.3),
          C.principled("blue", (0.08, 0.18, 0.6), roughness=0.7), rotation=(0, 0, math.radians(35)))

    C.sun_light("sun", (math.radians(45), math.radians(15), math.radians(35)), 4.0, angle_deg=0.5,
                color=(1.0, 0.96, 0.9))
    C.area_light("fill", (-2.2, 0.2, 1.4), 0.25, 60.0, color=(0.9, 0.95, 1.0))
    C.aim(bpy_obj("fill"), (0.0, 1.1, 0.2))

    C.camera("camera", (0.1, -1.6, 1.0), (0.05, 1.1, 0.2), lens=40.0)
    return scene


def bpy_obj(name):
    import bpy
    return bpy.data.objects[name]


if __name__ == "__main__":
    args = C.parse_args("jewel", default_size=(256, 192))
    build()
    C.render_jobs(args, "jewel", transparent=True)
