"""orbit: 16-frame camera orbit around car paint, brushed metal, glass, gold and walnut under an
HDRI and a sun (light passes).

Held-out ("report") sequence of the class issue 15 names after `metal` and `chrome`: a product
shot lit by an environment image and a strong sun, so that highlights, mirror images of the sun
and caustics slide over the objects while the camera moves. Never used to choose a setting.

On a dark, slightly glossy turntable disc over a concrete floor: a blue metallic car-paint body
(clear coat over a flaked base, showroom.car_paint), a brushed-steel column (anisotropic), a
polished gold torus standing upright (roughness 0.05: it mirrors the sun), a walnut block
(varnished wave rings) and a glass sphere that focuses the sun into a caustic. World: Blender's
bundled `courtyard.exr` studio light (an outdoor HDRI) at strength 0.8, plus a Sun lamp (0.5
degree disc) from the front right. Indirect clamp off: caustics and sun paths through the glass
and off the gold arrive as rare, very bright samples.

The camera orbits the group's centre by 2.5 degrees per frame at a constant height, keyed on
every frame (linear, extrapolated), so every frame has motion vectors both ways. The noisy
frames carry Blender's light passes; the references are Combined only.

    blender -b --factory-startup --python-exit-code 1 --python orbit.py -- --out DIR [--frames 1-16]
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402
import showroom as S  # noqa: E402  (its materials; its scene is not built on import)

CLAMP_INDIRECT = 0.0  # off: keep the caustics' and the sun's fireflies
FRAMES = (1, 16)
TARGET = (0.0, 0.0, 0.45)
ORBIT_RADIUS, ORBIT_HEIGHT = 4.2, 1.7
ORBIT_START_DEG, ORBIT_STEP_DEG = 20.0, -2.5


def hdri_world(scene, name, strength):
    """An environment image from Blender's bundled studio lights as the world."""
    folder = bpy.utils.system_resource("DATAFILES", path=os.path.join("studiolights", "world"))
    world = scene.world
    world.use_nodes = True
    nt = world.node_tree
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(os.path.join(folder, name))
    mapping = nt.nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(140.0))
    coords = nt.nodes.new("ShaderNodeTexCoord")
    nt.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs["Vector"], env.inputs["Vector"])
    bg = nt.nodes.get("Background")
    nt.links.new(env.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = strength
    return world


def build():
    scene = C.reset_scene()
    hdri_world(scene, "courtyard.exr", 0.8)
    # Sun 30 degrees up from the front right: its image sits on the gold torus and the car's
    # clear coat, and the glass sphere throws its caustic back towards the turntable's centre.
    C.sun_light("sun", (math.radians(60.0), 0.0, math.radians(35.0)), 5.0, angle_deg=0.5,
                color=(1.0, 0.94, 0.86))

    C.plane("floor", (0, 0, 0), (30, 30),
            C.noise_color("concrete", (0.33, 0.33, 0.34), (0.48, 0.47, 0.45), scale=3.0,
                          roughness=0.45, rough_variation=0.15, use_object=False))
    C.cylinder("turntable", (0, 0, 0.03), 1.9, 0.06,
               C.principled("turntable_black", (0.03, 0.03, 0.035), roughness=0.15), vertices=96)

    car = C.sphere("car_body", (-0.55, 0.35, 0.45), 1.0,
                   S.car_paint("car_paint_blue", (0.02, 0.08, 0.45), (0.25, 0.45, 0.9)))
    car.scale = (1.05, 0.55, 0.38)
    car.rotation_euler = (0, 0, math.radians(25))
    C.cylinder("brushed_column", (0.95, 0.75, 0.6), 0.2, 1.1,
               S.brushed_metal("brushed_steel", (0.72, 0.72, 0.74)))
    C.torus("gold_torus", (0.45, -0.55, 0.38), 0.3, 0.08,
            C.principled("polished_gold", (1.0, 0.77, 0.34), roughness=0.05, metallic=1.0),
            rotation=(math.radians(90), 0, math.radians(-30)))
    C.box("walnut_block", (-0.5, -0.75, 0.2), (0.55, 0.4, 0.34), S.walnut("walnut"),
          rotation=(0, 0, math.radians(-18)))
    C.sphere("glass_sphere", (0.05, -0.05, 0.31), 0.25, C.glass("clear_glass", ior=1.5))

    cam = C.camera("camera", (0, -ORBIT_RADIUS, ORBIT_HEIGHT), TARGET, lens=40.0)
    C.key_orbit(cam, TARGET, ORBIT_RADIUS, ORBIT_HEIGHT, ORBIT_START_DEG, ORBIT_STEP_DEG, FRAMES)
    scene.frame_start, scene.frame_end = FRAMES
    scene.render.fps = 24
    return scene


if __name__ == "__main__":
    args = C.parse_args("orbit", default_size=(192, 108), sequence=True)
    build()
    C.render_jobs(args, "orbit", clamp_indirect=CLAMP_INDIRECT, light_passes=True)
