"""room: a closed Cornell-box-like room lit almost only indirectly.

A lamp hidden on top of a hanging panel shines at the ceiling, plus a small warm emitter
("window") high on the right wall. Everything the camera sees is lit by one or more
diffuse bounces, so low-spp renders are very noisy.

    blender -b --factory-startup --python-exit-code 1 --python room.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

W, D, H = 4.0, 5.0, 3.0  # room: x in [-W/2, W/2], y in [-D/2, D/2], z in [0, H]


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.0, 0.0, 0.0), 0.0)

    white = C.principled("wall_white", (0.78, 0.78, 0.76), roughness=0.9)
    red = C.principled("wall_red", (0.70, 0.08, 0.06), roughness=0.9)
    green = C.principled("wall_green", (0.10, 0.55, 0.12), roughness=0.9)
    floor_mat = C.checker("floor_tiles", (0.62, 0.60, 0.56), (0.35, 0.33, 0.30), scale=2.0,
                          roughness=0.6)
    r90 = math.pi / 2
    C.plane("floor", (0, 0, 0), (W, D), floor_mat)
    C.plane("ceiling", (0, 0, H), (W, D), white, rotation=(math.pi, 0, 0))
    C.plane("wall_back", (0, D / 2, H / 2), (W, H), white, rotation=(r90, 0, 0))
    C.plane("wall_front", (0, -D / 2, H / 2), (W, H), white, rotation=(-r90, 0, 0))
    C.plane("wall_left", (-W / 2, 0, H / 2), (H, D), red, rotation=(0, r90, 0))
    C.plane("wall_right", (W / 2, 0, H / 2), (H, D), green, rotation=(0, -r90, 0))

    # Hanging panel with the lamp on top, aimed at the ceiling.
    panel_mat = C.principled("panel", (0.55, 0.55, 0.55), roughness=0.5)
    C.box("light_panel", (0.0, 0.6, 2.45), (1.8, 1.2, 0.05), panel_mat)
    C.cylinder("panel_rod_l", (-0.7, 0.6, 2.74), 0.015, 0.52, panel_mat, vertices=12)
    C.cylinder("panel_rod_r", (0.7, 0.6, 2.74), 0.015, 0.52, panel_mat, vertices=12)
    C.area_light("ceiling_lamp", (0.0, 0.6, 2.50), 1.5, 160.0, color=(1.0, 0.95, 0.88),
                 rotation=(math.pi, 0, 0), size_y=0.9)
    # Small warm "window" high on the right wall, facing into the room.
    win = C.plane("window", (W / 2 - 0.01, 1.4, 2.3), (0.5, 0.7),
                  C.emitter("window_light", (1.0, 0.8, 0.55), 5.0), rotation=(0, -r90, 0))
    win.visible_glossy = True

    # Objects.
    C.box("tall_box", (-0.75, 1.1, 0.9), (0.8, 0.8, 1.8), white, rotation=(0, 0, math.radians(22)))
    C.box("short_box", (0.8, 0.2, 0.45), (0.9, 0.9, 0.9),
          C.principled("box_blue", (0.15, 0.25, 0.6), roughness=0.7),
          rotation=(0, 0, math.radians(-18)))
    C.sphere("ball", (0.8, 0.2, 1.25), 0.35,
             C.principled("ball_orange", (0.85, 0.35, 0.05), roughness=0.25, specular=0.5))
    C.torus("ring", (-0.3, -0.15, 0.12), 0.35, 0.12,
            C.principled("ring_gold", (0.9, 0.7, 0.3), roughness=0.3, metallic=1.0))
    C.sphere("small_ball", (-1.25, 0.1, 0.25), 0.25,
             C.principled("ball_white", (0.9, 0.9, 0.9), roughness=0.05, specular=0.5))

    C.camera("camera", (0.0, -2.35, 1.45), (0.0, 1.0, 1.05), lens=22.0)
    return scene


if __name__ == "__main__":
    args = C.parse_args("room", default_size=(256, 192))
    build()
    C.render_jobs(args, "room")
