"""product: a product shot on a transparent background with a shadow catcher.

Held out: never used to choose settings (the artist's set-up no other sample has: Film >
Transparent, so the world is alpha 0, and a floor that is a shadow catcher, so the soft shadows
live in the alpha and the floor itself is not rendered). On the catcher: a glass perfume bottle
with a polished gold cap, a glazed ceramic vase, a brushed-steel cube and a matte red box, lit
by a large soft key light from the upper left, a small rim light from behind and a procedural
sky that the glass and metal reflect (but the camera sees as transparent). Most of the frame is
alpha 0; what remains is dominated by reflections and refraction.

    blender -b --factory-startup --python-exit-code 1 --python product.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def build():
    scene = C.reset_scene()
    C.sky_world(scene, 35.0, 120.0, strength=0.15)

    catcher = C.plane("catcher", (0, 1.0, 0), (10, 10), C.principled("catcher", (0.8, 0.8, 0.8), 0.5))
    catcher.is_shadow_catcher = True

    C.cylinder("bottle", (-0.55, 1.1, 0.3), 0.22, 0.6, C.glass("bottle_glass", ior=1.45), vertices=48)
    C.cylinder("cap", (-0.55, 1.1, 0.68), 0.09, 0.16,
               C.principled("cap_gold", (1.0, 0.77, 0.35), roughness=0.12, metallic=1.0), vertices=32)
    vase = C.sphere("vase", (0.25, 1.45, 0.35), 0.35,
                    C.principled("glaze", (0.85, 0.88, 0.92), roughness=0.12, specular=0.6))
    vase.scale = (0.8, 0.8, 1.0)
    C.box("steel_cube", (0.85, 0.75, 0.2), (0.4, 0.4, 0.4),
          C.principled("brushed", (0.75, 0.76, 0.78), roughness=0.3, metallic=1.0),
          rotation=(0, 0, math.radians(25)))
    C.box("red_box", (-0.1, 0.55, 0.12), (0.3, 0.22, 0.24),
          C.principled("red", (0.7, 0.08, 0.06), roughness=0.6), rotation=(0, 0, math.radians(-15)))

    C.area_light("key", (-2.0, -0.8, 2.4), 1.4, 90.0, color=(1.0, 0.97, 0.93))
    C.aim(bpy_obj("key"), (0.0, 1.0, 0.3))
    C.area_light("rim", (1.4, 3.0, 1.2), 0.4, 40.0, color=(0.9, 0.95, 1.0))
    C.aim(bpy_obj("rim"), (0.1, 1.1, 0.4))

    C.camera("camera", (0.2, -2.0, 1.2), (0.1, 1.0, 0.3), lens=45.0)
    return scene


def bpy_obj(name):
    import bpy
    return bpy.data.objects[name]


if __name__ == "__main__":
    args = C.parse_args("product", default_size=(256, 192))
    build()
    C.render_jobs(args, "product", transparent=True)
