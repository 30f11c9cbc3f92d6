"""metal: 16-frame camera orbit around polished metal under a small, strong sun (light passes).

An open set: a glossy checkered floor (dielectric, roughness 0.12) and a low brick wall (sky above
it: the Env pass is not empty) under a
dim blue world, lit by a Sun lamp (0.6 degree disc, strong) from the upper left, a little behind
the camera. A polished gold sphere (Principled, metallic, roughness 0.03) mirrors the sun as a
tiny, very bright spot; a brushed-steel torus (roughness 0.25), a small glass sphere (so the
Transmission passes carry something) and a noise-textured clay cube complete it.

The camera orbits the gold sphere by 3 degrees per frame, keyframed on every frame with linear
interpolation and linear extrapolation (every frame has motion vectors both ways), so the sun's
reflection slides across the sphere while the surface under it moves the other way.

Rendered with indirect clamping off (common.render_jobs clamp 0), as a production render would
be: floor -> metal/glass -> sun paths arrive as rare, very bright samples (fireflies). The noisy
frames carry Blender's light passes too (DiffDir/Ind/Col, GlossDir/Ind/Col, TransDir/Ind/Col,
Emit, Env), which sum to Combined.

    blender -b --factory-startup --python-exit-code 1 --python metal.py -- --out DIR [--frames 1-16]
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

CLAMP_INDIRECT = 0.0  # off: keep the fireflies a real render has
FRAMES = (1, 16)
TARGET = (0.0, 0.4, 0.45)  # the camera aims at the gold sphere's centre
ORBIT_RADIUS, ORBIT_HEIGHT = 3.6, 1.25
ORBIT_START_DEG, ORBIT_STEP_DEG = -22.5, 3.0  # azimuth of the camera around TARGET, per frame


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.35, 0.45, 0.7), 0.35)
    r90 = math.pi / 2

    C.plane("floor", (0, 1.0, 0), (14, 10),
            C.checker("floor_glossy_checker", (0.62, 0.60, 0.56), (0.10, 0.10, 0.11), scale=1.5,
                      roughness=0.12))
    C.plane("wall_back", (0, 3.2, 0.65), (14, 1.3),
            C.brick("wall_brick", (0.58, 0.26, 0.16), (0.45, 0.36, 0.28), scale=2.2,
                    roughness=0.8), rotation=(r90, 0, 0))

    C.sphere("gold_sphere", TARGET, 0.45,
             C.principled("polished_gold", (1.0, 0.77, 0.34), roughness=0.03, metallic=1.0))
    C.torus("steel_torus", (1.15, 1.1, 0.36), 0.34, 0.12,
            C.principled("brushed_steel", (0.63, 0.64, 0.67), roughness=0.25, metallic=1.0),
            rotation=(math.radians(65), 0, math.radians(-25)))
    C.sphere("glass_ball", (-0.75, -0.35, 0.2), 0.2, C.glass("clear_glass", ior=1.45, color=(0.92, 0.97, 1.0)))
    C.box("clay_cube", (-1.35, 1.3, 0.3), (0.6, 0.6, 0.6),
          C.noise_color("clay_noise", (0.20, 0.35, 0.55), (0.80, 0.70, 0.45), scale=4.0,
                        roughness=0.6), rotation=(0, 0, math.radians(30)))

    # Sun 35 degrees up from the left, a little behind the camera: its mirror image sits on the
    # upper left of the gold sphere and the objects cast hard shadows to the right.
    el, az = math.radians(35.0), math.radians(-60.0)
    C.sun_light("sun", (r90 - el, 0, az), 6.0, angle_deg=0.6, color=(1.0, 0.94, 0.85))

    cam = C.camera("camera", (0.0, -3.2, ORBIT_HEIGHT), TARGET, lens=35.0)
    C.key_orbit(cam, TARGET, ORBIT_RADIUS, ORBIT_HEIGHT, ORBIT_START_DEG, ORBIT_STEP_DEG, FRAMES)
    scene.frame_start, scene.frame_end = FRAMES
    scene.render.fps = 24
    return scene


if __name__ == "__main__":
    args = C.parse_args("metal", default_size=(256, 144), sequence=True)
    build()
    C.render_jobs(args, "metal", clamp_indirect=CLAMP_INDIRECT, light_passes=True)
