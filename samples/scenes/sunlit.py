"""sunlit: an attic lit by the sun through a narrow window slit ("mirrors under a sun").

A closed attic (wave-striped end walls, brick side walls, sloped plaster roof, wave-grained
plank floor) whose only opening is a narrow horizontal slit in the left wall. A Sun lamp (0.7 degree
disc) shines through it and draws a hard bright patch on the floor; a weak blue sky is the only
other light, and it too enters only through the slit. A polished gold sphere (roughness 0.05)
stands in the sun, so its highlight is a tiny, very bright spot; a rough steel ring, a checkered
crate and a diffuse clay Suzanne sit in the indirectly lit rest of the room.

    blender -b --factory-startup --python-exit-code 1 --python sunlit.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

W, D = 5.0, 6.0        # attic: x in [-W/2, W/2], y in [-D/2, D/2]
KNEE, RIDGE = 1.8, 3.0  # side-wall height and ridge height (roof slopes from x=+-W/2 to x=0)
T = 0.2                 # wall thickness of the slit wall
SLIT_Y, SLIT_Z = (-1.5, 1.5), (0.9, 1.3)  # slit extent in the left wall


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.45, 0.6, 1.0), 3.0)

    r90 = math.pi / 2
    floor = C.wave_stripes("floor_planks", (0.60, 0.40, 0.22), (0.36, 0.21, 0.10), scale=2.2,
                           roughness=0.75, use_object=False)
    C.plane("floor", (0, 0, 0), (W, D), floor)
    brick = C.brick("side_brick", (0.66, 0.36, 0.22), (0.55, 0.45, 0.36), scale=1.6, roughness=0.85)
    stripes = C.wave_stripes("end_stripes", (0.80, 0.76, 0.62), (0.25, 0.40, 0.45), scale=1.5,
                             roughness=0.6, use_object=False)
    C.plane("wall_back", (0, D / 2, RIDGE / 2), (W, RIDGE), stripes, rotation=(r90, 0, 0))
    C.plane("wall_front", (0, -D / 2, RIDGE / 2), (W, RIDGE), stripes, rotation=(-r90, 0, 0))
    C.plane("wall_right", (W / 2, 0, KNEE / 2), (KNEE, D), brick, rotation=(0, -r90, 0))
    plaster = C.noise_color("roof_plaster", (0.72, 0.70, 0.66), (0.86, 0.85, 0.82), scale=3.0,
                            roughness=0.9)
    half = math.hypot(W / 2, RIDGE - KNEE)
    tilt = math.atan2(RIDGE - KNEE, W / 2)
    C.plane("roof_left", (-W / 4, 0, (KNEE + RIDGE) / 2), (half + 0.05, D), plaster,
            rotation=(0, math.pi - tilt, 0))
    C.plane("roof_right", (W / 4, 0, (KNEE + RIDGE) / 2), (half + 0.05, D), plaster,
            rotation=(0, math.pi + tilt, 0))

    # Left wall as four brick blocks around the slit (thick, so the slit casts a clean patch).
    x = -W / 2 - T / 2
    (y0, y1), (z0, z1) = SLIT_Y, SLIT_Z
    for name, yc, ys, zc, zs in [
            ("below", 0.0, D, z0 / 2, z0),
            ("above", 0.0, D, (z1 + KNEE + 0.3) / 2, KNEE + 0.3 - z1),
            ("left", (-D / 2 + y0) / 2, y0 + D / 2, (z0 + z1) / 2, z1 - z0),
            ("right", (y1 + D / 2) / 2, D / 2 - y1, (z0 + z1) / 2, z1 - z0)]:
        C.box(f"wall_left_{name}", (x, yc, zc), (T, ys, zs), brick)

    # Sun from the left (-x), 27 degrees up, slightly from the front: through the slit onto
    # the floor around x = 0.
    el, az = math.radians(22.0), math.radians(10.0)
    C.sun_light("sun", (r90 - el, 0, -r90 + az), 60.0, angle_deg=0.7, color=(1.0, 0.93, 0.82))

    C.sphere("gold_sphere", (0.15, 0.2, 0.3), 0.3,
             C.principled("polished_gold", (1.0, 0.77, 0.34), roughness=0.05, metallic=1.0))
    C.torus("steel_ring", (0.9, 2.1, 0.42), 0.36, 0.12,
            C.principled("rough_steel", (0.62, 0.63, 0.66), roughness=0.45, metallic=1.0),
            rotation=(math.radians(70), 0, math.radians(30)))
    C.monkey("suzanne", (-1.1, 1.6, 0.5), 1.0,
             C.principled("suzanne_clay", (0.55, 0.62, 0.50), roughness=1.0, specular=0.2),
             rotation=(math.radians(-5), 0, math.radians(-150)))
    C.box("crate", (1.5, 1.0, 0.3), (0.6, 0.6, 0.6),
          C.checker("crate_checker", (0.70, 0.62, 0.45), (0.30, 0.22, 0.14), scale=5.0,
                    roughness=0.8), rotation=(0, 0, math.radians(20)))

    C.camera("camera", (1.7, -2.3, 1.35), (-0.5, 0.7, 0.55), lens=26.0)
    return scene


if __name__ == "__main__":
    args = C.parse_args("sunlit", default_size=(256, 192))
    build()
    C.render_jobs(args, "sunlit")
