"""showroom: car paint, brushed metal, glass and walnut under a procedural sky and a sun.

A grey concrete showroom floor and a pale back wall, open to a Nishita sky (procedural, no
image; its own sun disc off) and lit by a Sun lamp (0.55 degree disc) from the left.
A car-body-like ellipsoid in red metallic car paint (clear coat over a base whose colour and
roughness follow a fine noise, like metal flakes), a brushed-steel column (anisotropic), a
walnut plinth (wave rings and noise grain) and a glass sphere that focuses the sun into a
caustic on the floor.

This is the one scene rendered with indirect clamping off (common.render_jobs clamp 0): paths
floor -> glass -> sun are found only by BSDF sampling, so the caustic arrives as rare, very
bright samples (fireflies), as in real production renders of such scenes.

    blender -b --factory-startup --python-exit-code 1 --python showroom.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

CLAMP_INDIRECT = 0.0  # off: keep the caustic fireflies


def _principled_nodes(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    return mat, nt, nt.nodes.get("Principled BSDF")


def car_paint(name, base, flake):
    """Clear coat over a metallic base; a fine noise varies base colour and roughness (flakes)."""
    mat, nt, bsdf = _principled_nodes(name)
    tc = nt.nodes.new("ShaderNodeTexCoord")
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 180.0
    noise.inputs["Detail"].default_value = 2.0
    nt.links.new(tc.outputs["Object"], noise.inputs["Vector"])
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].position = 0.4
    ramp.color_ramp.elements[0].color = (*base, 1.0)
    ramp.color_ramp.elements[1].position = 0.6
    ramp.color_ramp.elements[1].color = (*flake, 1.0)
    nt.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    rough = nt.nodes.new("ShaderNodeMapRange")
    rough.inputs["To Min"].default_value = 0.15
    rough.inputs["To Max"].default_value = 0.45
    nt.links.new(noise.outputs["Fac"], rough.inputs["Value"])
    nt.links.new(rough.outputs["Result"], bsdf.inputs["Roughness"])
    bsdf.inputs["Metallic"].default_value = 0.7
    bsdf.inputs["Clearcoat"].default_value = 1.0
    bsdf.inputs["Clearcoat Roughness"].default_value = 0.03
    return mat


def brushed_metal(name, color):
    mat, nt, bsdf = _principled_nodes(name)
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Metallic"].default_value = 1.0
    bsdf.inputs["Roughness"].default_value = 0.3
    bsdf.inputs["Anisotropic"].default_value = 0.9
    return mat


def walnut(name):
    """Ring pattern (wave rings, distorted) through a dark-to-mid brown ramp, lacquered."""
    mat, nt, bsdf = _principled_nodes(name)
    tc = nt.nodes.new("ShaderNodeTexCoord")
    mp = nt.nodes.new("ShaderNodeMapping")
    mp.inputs["Scale"].default_value = (1.0, 6.0, 1.0)
    nt.links.new(tc.outputs["Object"], mp.inputs["Vector"])
    wave = nt.nodes.new("ShaderNodeTexWave")
    wave.wave_type = "RINGS"
    wave.inputs["Scale"].default_value = 3.0
    wave.inputs["Distortion"].default_value = 6.0
    wave.inputs["Detail"].default_value = 4.0
    nt.links.new(mp.outputs["Vector"], wave.inputs["Vector"])
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.06, 0.03, 0.015, 1.0)
    ramp.color_ramp.elements[1].color = (0.30, 0.16, 0.07, 1.0)
    nt.links.new(wave.outputs["Fac"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.35
    bsdf.inputs["Clearcoat"].default_value = 0.5
    return mat


def build():
    scene = C.reset_scene()
    # Sun 38 degrees up, from the left and a little behind the objects (as seen from the
    # camera), so the glass casts its caustic to the right onto the floor.
    el, rot = 38.0, 252.5
    C.sky_world(scene, el, rot, strength=0.25)
    sun_dir_rot = (math.radians(90.0 - el), 0.0, math.radians(rot))
    C.sun_light("sun", sun_dir_rot, 4.0, angle_deg=0.55, color=(1.0, 0.95, 0.88))

    C.plane("floor", (0, 0, 0), (30, 30),
            C.noise_color("concrete", (0.30, 0.30, 0.31), (0.45, 0.44, 0.43), scale=2.5,
                          roughness=0.35, rough_variation=0.15, use_object=False))
    C.plane("back_wall", (0, 4.0, 2.5), (30, 5), C.principled("wall_paint", (0.80, 0.80, 0.78),
                                                                roughness=0.8),
            rotation=(math.pi / 2, 0, 0))

    car = C.sphere("car_body", (-0.9, 1.4, 0.5), 1.0, car_paint("car_paint", (0.50, 0.02, 0.03),
                                                                (0.85, 0.25, 0.20)))
    car.scale = (1.3, 0.6, 0.42)
    car.rotation_euler = (0, 0, math.radians(-15))
    C.cylinder("brushed_column", (1.4, 2.2, 0.9), 0.28, 1.8,
               brushed_metal("brushed_steel", (0.75, 0.75, 0.77)))
    C.box("walnut_plinth", (0.55, 0.6, 0.25), (0.9, 0.7, 0.5), walnut("walnut"),
          rotation=(0, 0, math.radians(12)))
    C.sphere("glass_sphere", (0.55, 0.6, 0.85), 0.35, C.glass("clear_glass"))
    C.sphere("glass_ball_floor", (-0.1, -0.3, 0.3), 0.3, C.glass("clear_glass_2"))

    C.camera("camera", (0.3, -4.2, 1.6), (0.1, 1.0, 0.45), lens=35.0)
    return scene


if __name__ == "__main__":
    args = C.parse_args("showroom", default_size=(256, 192))
    build()
    C.render_jobs(args, "showroom", clamp_indirect=CLAMP_INDIRECT)
