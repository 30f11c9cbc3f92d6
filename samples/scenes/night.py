"""night: a street corner at night, rendered at its physical brightness ("exposure").

Held out: never used to choose settings. The render is as dark as the light in it: no film
exposure, so its mean luminance is about 0.01 (the other stills sit at 0.2-0.56, where the
filters' constants were set). A sodium street lamp (a small warm point light) and a lit shop
window (a warm emissive pane and a soft area light behind it) light a brick wall, an asphalt
street with a glossy puddle, a painted bench, a metal bin and a parked box-car with glossy
paint; a faint blue moonlit sky fills the shadows. Highlights on the wet puddle, the bin and the
car paint stand hundreds of times above the shadows.

    blender -b --factory-startup --python-exit-code 1 --python night.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def build():
    scene = C.reset_scene()
    C.sky_world(scene, -4.0, 200.0, strength=0.005, sky_type="NISHITA")
    r90 = math.pi / 2

    asphalt = C.noise_color("asphalt", (0.05, 0.05, 0.055), (0.14, 0.14, 0.15), scale=60.0,
                            roughness=0.8)
    C.plane("street", (0, 4, 0), (20, 16), asphalt)
    puddle = C.principled("puddle", (0.02, 0.02, 0.025), roughness=0.03, specular=0.6)
    C.plane("puddle", (0.6, 2.6, 0.003), (1.6, 0.9), puddle)
    bricks = C.brick("bricks", (0.42, 0.16, 0.1), (0.3, 0.12, 0.08), scale=5.0)
    C.plane("wall", (0, 7.0, 2.5), (20, 5), bricks, rotation=(r90, 0, 0))

    # The shop window: a warm pane in the wall, with a soft light behind it into the street.
    C.plane("window", (-2.4, 6.98, 1.5), (2.2, 1.4), C.emitter("shop", (1.0, 0.78, 0.5), 0.4),
            rotation=(r90, 0, 0))
    C.area_light("shop_light", (-2.4, 6.9, 1.5), 2.0, 4.5, color=(1.0, 0.8, 0.55),
                 rotation=(-r90, 0, 0), size_y=1.3)

    paint = C.principled("car_paint", (0.35, 0.02, 0.03), roughness=0.15, metallic=0.3)
    C.box("car_body", (2.3, 4.6, 0.55), (3.6, 1.6, 0.7), paint)
    C.box("car_cabin", (2.1, 4.6, 1.15), (1.9, 1.4, 0.55), paint)
    steel = C.principled("bin_steel", (0.7, 0.7, 0.72), roughness=0.25, metallic=1.0)
    C.cylinder("bin", (-0.6, 5.4, 0.45), 0.28, 0.9, steel, vertices=32)
    wood = C.principled("bench_paint", (0.1, 0.3, 0.15), roughness=0.5)
    C.box("bench_seat", (-1.3, 6.2, 0.45), (1.6, 0.4, 0.06), wood)
    C.box("bench_back", (-1.3, 6.4, 0.75), (1.6, 0.05, 0.5), wood)

    # The sodium lamp: a pole and a small warm bulb.
    C.cylinder("pole", (1.0, 6.3, 1.9), 0.05, 3.8, steel, vertices=16)
    C.sphere("bulb", (1.0, 6.0, 3.7), 0.07, C.emitter("sodium", (1.0, 0.62, 0.25), 10.0))
    C.point_light("lamp", (1.0, 6.0, 3.62), 0.05, 30.0, (1.0, 0.62, 0.25))

    C.camera("camera", (-0.2, -2.0, 1.5), (0.4, 5.0, 1.0), lens=30.0)
    return scene


if __name__ == "__main__":
    args = C.parse_args("night", default_size=(256, 192))
    build()
    C.render_jobs(args, "night")
