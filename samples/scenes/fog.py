"""fog: a hazy warehouse bay with light shafts, a spot cone and neon tubes ("volumes").

Held out: never used to choose settings. Everything sits inside a box of homogeneous fog
(Principled Volume, density 0.05 per metre), so most pixels' light comes from in-scattering
along the ray, which no feature pass describes: where the camera sees fog in front of a wall
the Normal, Depth and albedo passes are the wall's, while the colour carries the fog's noise and
the shafts' edges. A Sun lamp shines through four vertical gaps in the left wall (four shafts
across the floor and through the air), a spot lamp above the right side draws a visible cone
onto a checkered floor, and two neon tubes (cyan and magenta emitters) glow on the back wall.
Crates (checker), a brushed metal drum, a clay Suzanne and a glossy sphere stand on the floor.

    blender -b --factory-startup --python-exit-code 1 --python fog.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

W, D, H = 8.0, 8.0, 4.0  # bay: x in [-W/2, W/2], y in [-D/2, D/2], z in [0, H]
GAPS = [-2.4, -1.0, 0.4, 1.8]  # y of the four gaps in the left wall
GAP_W = 0.25
DENSITY = 0.05


def fog_material():
    mat, nt, out = C.bare_material("fog")
    vol = nt.nodes.new("ShaderNodeVolumePrincipled")
    vol.inputs["Color"].default_value = (0.85, 0.87, 0.9, 1.0)
    vol.inputs["Density"].default_value = DENSITY
    vol.inputs["Anisotropy"].default_value = 0.3
    nt.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    return mat


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.5, 0.6, 0.8), 0.4)
    r90 = math.pi / 2

    floor = C.checker("floor_checker", (0.55, 0.54, 0.5), (0.2, 0.2, 0.21), scale=6.0,
                      roughness=0.55)
    C.plane("floor", (0, 0, 0), (W, D), floor)
    concrete = C.noise_color("concrete", (0.5, 0.49, 0.46), (0.66, 0.64, 0.6), scale=4.0,
                             roughness=0.9)
    C.plane("wall_back", (0, D / 2, H / 2), (W, H), concrete, rotation=(r90, 0, 0))
    C.plane("wall_right", (W / 2, 0, H / 2), (H, D), concrete, rotation=(0, -r90, 0))
    C.plane("ceiling", (0, 0, H), (W, D), concrete, rotation=(math.pi, 0, 0))
    # Left wall as solid boxes between the four gaps: four sun shafts.
    brick = C.brick("left_brick", (0.55, 0.3, 0.2), (0.45, 0.36, 0.3), scale=1.5, roughness=0.85)
    edges = [-D / 2] + [g for y in GAPS for g in (y - GAP_W / 2, y + GAP_W / 2)] + [D / 2]
    for i in range(0, len(edges), 2):
        y0, y1 = edges[i], edges[i + 1]
        C.box(f"wall_left_{i // 2}", (-W / 2 - 0.1, (y0 + y1) / 2, H / 2), (0.2, y1 - y0, H), brick)

    C.box("fog", (0, 0, H / 2), (W - 0.02, D - 0.02, H - 0.02), fog_material())

    el, az = math.radians(35.0), math.radians(-12.0)
    C.sun_light("sun", (r90 - el, 0, -r90 + az), 25.0, angle_deg=0.6, color=(1.0, 0.9, 0.75))

    spot = bpy.data.lights.new("spot", "SPOT")
    spot.energy = 900.0
    spot.spot_size = math.radians(32.0)
    spot.spot_blend = 0.15
    spot.shadow_soft_size = 0.05
    spot.color = (1.0, 0.95, 0.85)
    so = bpy.data.objects.new("spot", spot)
    so.location = (2.0, 1.0, H - 0.15)
    bpy.context.scene.collection.objects.link(so)
    C.aim(so, (2.0, 0.6, 0.0))

    C.cylinder("neon_cyan", (-1.2, D / 2 - 0.08, 2.6), 0.03, 2.2, C.emitter("cyan", (0.2, 0.9, 1.0), 40.0),
               rotation=(0, r90, 0))
    C.cylinder("neon_magenta", (1.4, D / 2 - 0.08, 3.1), 0.03, 1.6,
               C.emitter("magenta", (1.0, 0.2, 0.8), 40.0), rotation=(0, r90, 0))

    crate = C.checker("crate_checker", (0.7, 0.6, 0.42), (0.32, 0.24, 0.15), scale=5.0, roughness=0.8)
    C.box("crate_a", (-1.6, 1.2, 0.4), (0.8, 0.8, 0.8), crate, rotation=(0, 0, math.radians(15)))
    C.box("crate_b", (-1.4, 1.3, 1.1), (0.6, 0.6, 0.6), crate, rotation=(0, 0, math.radians(40)))
    C.cylinder("drum", (2.0, 0.6, 0.5), 0.35, 1.0,
               C.principled("drum_metal", (0.55, 0.2, 0.12), roughness=0.3, metallic=1.0))
    C.monkey("suzanne", (0.0, 0.2, 0.45), 0.9, C.principled("clay", (0.6, 0.62, 0.55), roughness=1.0),
             rotation=(0, 0, math.radians(200)))
    C.sphere("glossy_ball", (0.9, -0.8, 0.3), 0.3,
             C.principled("glossy_ball", (0.1, 0.15, 0.5), roughness=0.08, specular=0.8))

    C.camera("camera", (0.3, -3.7, 1.6), (0.0, 1.5, 1.2), lens=24.0)
    return scene


if __name__ == "__main__":
    args = C.parse_args("fog", default_size=(256, 192))
    build()
    C.render_jobs(args, "fog", clamp_indirect=C.CLAMP_INDIRECT)
