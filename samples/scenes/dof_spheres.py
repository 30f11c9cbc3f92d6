"""dof_spheres: a third depth-of-field scene, held out (issue 17: never used to choose a setting;
the sweep's figures on it are reported as they come). A loose group of spheres at several
depths on a checkered floor: a matt orange one and a striped one near the lens, a noise-textured
one in focus, a glossy metal one, a blue one, a checkered one and a pale one further back, a
string of small glowing bulbs (bokeh discs) before a brick wall far behind (distant floor and a
strip of sky to its right), under a gradient sky and a sun; 85 mm at f/1.2 (sensor 36 mm)
focused on the textured sphere (2.01 m).

Circle of confusion across the 128 px width, coc = lens^2 / (fstop * (focus - lens))
* |z - focus| / z * width / sensor (thin lens; Blender's pinhole-aperture form, with focus for
focus - lens, is 4 % less), at the centres' planar depths z: orange sphere (0.86 m) 14.9 px,
striped (1.13 m) 8.8, focus sphere 0, metal (2.71 m) 2.8, blue (3.80 m) 5.2, checkered (5.97 m)
7.4, pale (6.95 m) 7.9, bulbs (7.92 m) 8.3, wall (8.90 m) 8.6, the horizon 11.1. configure()
prints them for the built camera.

    (per-sample form) per_sample.py --scene dof_spheres
"""
import math
import os
import sys

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

LENS = 85.0
FSTOP = 1.2


def gradient_sky(scene, horizon, zenith, ground, strength=1.0):
    """An HDRI-like world without an image or a precomputed sky: colour by the view direction's
    height (ground below the horizon, horizon to zenith above it), importance-sampled."""
    world = scene.world
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes.get("Background")
    tc = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    cr = ramp.color_ramp
    cr.elements[0].position, cr.elements[0].color = 0.5, (*ground, 1.0)
    cr.elements[1].position, cr.elements[1].color = 1.0, (*zenith, 1.0)
    cr.elements.new(0.52).color = (*horizon, 1.0)
    mr = nt.nodes.new("ShaderNodeMapRange")  # z in [-1, 1] to [0, 1]
    mr.inputs["From Min"].default_value = -1.0
    mr.inputs["From Max"].default_value = 1.0
    nt.links.new(tc.outputs["Generated"], sep.inputs["Vector"])
    nt.links.new(sep.outputs["Z"], mr.inputs["Value"])
    nt.links.new(mr.outputs["Result"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = strength
    # The default 1024 px importance map takes ~1 s to build for every (sub-)render; a smooth
    # gradient needs far less.
    world.cycles.sampling_method = "MANUAL"
    world.cycles.sample_map_resolution = 64
    return world


def coc_px(scene, z):
    """Thin-lens circle of confusion (pixels across the image width) at planar depth z (m)."""
    d = scene.camera.data
    f, s = d.lens * 1e-3, d.dof.focus_distance
    return f * f / (d.dof.aperture_fstop * (s - f)) * abs(z - s) / z \
        * scene.render.resolution_x / (d.sensor_width * 1e-3)


def build():
    scene = C.reset_scene()
    gradient_sky(scene, horizon=(0.85, 0.8, 0.7), zenith=(0.25, 0.45, 0.9), ground=(0.25, 0.22, 0.2),
                 strength=0.7)
    C.plane("floor", (0, 45.0, 0), (100, 100),
            C.checker("floor_tiles", (0.5, 0.48, 0.44), (0.16, 0.18, 0.22), scale=5.0, roughness=0.55))
    # The wall stops short of the right edge: distant floor and a strip of sky show there.
    C.plane("wall", (-1.6, 9.0, 0.75), (4.8, 1.5),
            C.brick("wall_brick", (0.6, 0.22, 0.12), (0.35, 0.3, 0.22), mortar=(0.85, 0.83, 0.78), scale=1.5,
                    roughness=0.85),
            rotation=(math.pi / 2, 0, 0))

    # Near the lens (blurred): a matt orange sphere at the left edge, a striped one at the bottom.
    C.sphere("near_orange", (-0.16, 0.85, 0.2), 0.045, C.principled("near_orange", (0.9, 0.45, 0.08),
                                                                     roughness=0.6))
    C.sphere("near_stripes", (0.17, 1.1, 0.06), 0.06,
             C.wave_stripes("near_stripes", (0.95, 0.95, 0.9), (0.55, 0.1, 0.45), scale=12.0))
    # In focus: a noise-textured sphere resting on the floor.
    subject = C.sphere("focus_ball", (0.0, 2.0, 0.11), 0.11,
                       C.noise_color("focus_noise", (0.1, 0.45, 0.2), (0.9, 0.85, 0.3), scale=12.0,
                                     roughness=0.35, rough_variation=0.15))
    # Behind it, more and more blurred.
    C.sphere("metal_ball", (-0.35, 2.7, 0.14), 0.14,
             C.principled("metal_ball", (0.92, 0.9, 0.88), roughness=0.08, metallic=1.0))
    C.sphere("blue_ball", (0.55, 3.8, 0.18), 0.18, C.principled("blue_ball", (0.1, 0.25, 0.8),
                                                                 roughness=0.3))
    C.sphere("far_checker", (-0.9, 6.0, 0.3), 0.3,
             C.checker("far_checker", (0.9, 0.9, 0.88), (0.8, 0.15, 0.1), scale=5.0, roughness=0.4,
                       use_object=True))
    C.sphere("far_pale", (-0.25, 7.0, 0.35), 0.35,
             C.principled("far_pale", (0.85, 0.82, 0.75), roughness=0.5))
    # A string of small bulbs in front of the wall: bokeh discs.
    bulb_colours = [(1.0, 0.75, 0.4), (1.0, 0.9, 0.7), (0.6, 0.8, 1.0)]
    for i in range(7):
        x = -1.7 + 0.5 * i
        C.sphere(f"bulb_{i}", (x, 8.0, 0.56 + 0.06 * math.cos(1.7 * i)), 0.025,
                 C.emitter(f"bulb_{i}", bulb_colours[i % 3], strength=24.0), segments=16, rings=8)

    C.sun_light("sun", (math.radians(50), 0, math.radians(-35)), 2.0, angle_deg=3.0,
                color=(1.0, 0.95, 0.88))
    cam = C.camera("camera", (0.0, 0.0, 0.35), (0.0, 2.0, 0.12), lens=LENS)
    d = cam.data.dof
    d.use_dof = True
    d.aperture_fstop = FSTOP
    bpy.context.view_layer.update()
    fwd = cam.matrix_world.to_3x3() @ Vector((0, 0, -1))
    d.focus_distance = (subject.location - cam.location).dot(fwd)
    return scene


def configure(scene):
    """Prints the circle of confusion (pixels) at the centre of every object but the floor."""
    cam = scene.camera
    fwd = cam.matrix_world.to_3x3() @ Vector((0, 0, -1))
    figures = {o.name: round(coc_px(scene, (o.location - cam.location).dot(fwd)), 2)
               for o in scene.objects if o.type == "MESH" and o.name != "floor"}
    print(f"dof_spheres: focus {cam.data.dof.focus_distance:.3f} m, coc px {figures}", flush=True)
