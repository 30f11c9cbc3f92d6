"""glossy: procedurally textured and glossy/metallic objects on a checker floor.

Metal spheres of increasing roughness (tinted Glossy BSDFs, so the GlossCol pass varies), a noise-textured plastic Suzanne, a brick cube, a
wave-striped cylinder and a gold torus, lit by two area lights (one large and soft, one small
and hard) under a dim sky-blue world. Albedo varies through checker, brick, noise and wave
textures; roughness varies per object and, on the Suzanne, per pixel.

    blender -b --factory-startup --python-exit-code 1 --python glossy.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.35, 0.45, 0.6), 0.15)

    floor = C.checker("floor_checker", (0.75, 0.74, 0.70), (0.08, 0.08, 0.09), scale=1.5,
                      roughness=0.35)
    C.plane("floor", (0, 1.5, 0), (14, 14), floor)
    back = C.brick("back_brick", (0.55, 0.22, 0.12), (0.42, 0.30, 0.22), scale=1.2, roughness=0.8)
    C.plane("back_wall", (0, 5.0, 3.0), (14, 6), back, rotation=(math.pi / 2, 0, 0))

    # Row of metal spheres, roughness 0.02 .. 0.5.
    for i, (rough, col) in enumerate([(0.02, (0.95, 0.95, 0.95)), (0.12, (0.95, 0.75, 0.45)),
                                      (0.25, (0.90, 0.55, 0.45)), (0.5, (0.70, 0.75, 0.80))]):
        C.sphere(f"metal_{i}", (-1.8 + 1.2 * i, 2.2, 0.45), 0.45,
                 C.glossy_bsdf(f"metal_r{rough}", col, roughness=rough))
    C.monkey("suzanne", (-1.75, 0.3, 0.55), 0.9,
             C.noise_color("suzanne_noise", (0.05, 0.25, 0.55), (0.85, 0.75, 0.2), scale=4.0,
                           roughness=0.25, rough_variation=0.2),
             rotation=(math.radians(-10), 0, math.radians(-25)))
    C.box("brick_cube", (0.35, 0.4, 0.35), (0.7, 0.7, 0.7),
          C.brick("cube_brick", (0.7, 0.7, 0.72), (0.3, 0.32, 0.4), scale=4.0, roughness=0.6),
          rotation=(0, 0, math.radians(30)))
    C.cylinder("stripes", (1.6, 0.9, 0.5), 0.35, 1.0,
               C.wave_stripes("cyl_waves", (0.9, 0.9, 0.85), (0.1, 0.35, 0.2), scale=2.5,
                              roughness=0.15))
    C.torus("gold_ring", (0.9, -0.4, 0.1), 0.3, 0.1,
            C.principled("gold", (1.0, 0.76, 0.33), roughness=0.18, metallic=1.0),
            rotation=(0, 0, 0))

    C.area_light("key", (3.0, -1.5, 4.0), 2.5, 380.0, color=(1.0, 0.96, 0.9))
    C.aim(bpy_obj("key"), (0.0, 1.0, 0.3))
    C.area_light("rim", (-3.0, 3.5, 2.5), 0.4, 150.0, color=(0.8, 0.9, 1.0))
    C.aim(bpy_obj("rim"), (-0.5, 1.0, 0.5))

    C.camera("camera", (0.6, -4.2, 2.2), (0.0, 1.2, 0.5), lens=35.0)
    return scene


def bpy_obj(name):
    import bpy
    return bpy.data.objects[name]


if __name__ == "__main__":
    args = C.parse_args("glossy", default_size=(256, 192))
    build()
    C.render_jobs(args, "glossy")
