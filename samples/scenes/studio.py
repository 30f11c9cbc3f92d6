"""studio: hair, subsurface wax, an emissive screen and back-lit leaves on a photo table.

Held out: never used to choose settings (content no other sample has: hair strands, light
under a surface, a textured emitter, light through thin leaves). On a pale cyclorama-like
backdrop (floor and back wall): a furry ball (particle hair, Principled Hair BSDF, strands far
thinner than a pixel), a wax pillar candle (Principled subsurface, a small bright flame that is
an emitter), a small screen showing an emissive wave pattern, and two leaves (Translucent +
Diffuse, noise-veined) lit from behind. A soft key light from the left front, a small warm rim
spot from behind and a dim world.

    blender -b --factory-startup --python-exit-code 1 --python studio.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def hair_material():
    mat, nt, out = C.bare_material("fur")
    hair = nt.nodes.new("ShaderNodeBsdfHairPrincipled")
    hair.parametrization = "MELANIN"
    hair.inputs["Melanin"].default_value = 0.55
    hair.inputs["Roughness"].default_value = 0.35
    nt.links.new(hair.outputs["BSDF"], out.inputs["Surface"])
    return mat


def wax_material():
    mat = C.principled("wax", (0.92, 0.82, 0.62), roughness=0.35)
    _, bsdf = C._nodes(mat)
    bsdf.inputs["Subsurface"].default_value = 0.6
    bsdf.inputs["Subsurface Radius"].default_value = (0.12, 0.06, 0.03)
    bsdf.inputs["Subsurface Color"].default_value = (0.95, 0.7, 0.4, 1.0)
    return mat


def ramp_texture(nt, node_type, inputs, c0, c1):
    """A texture node (object coordinates) through a two-colour ramp: the ramp node."""
    tc = nt.nodes.new("ShaderNodeTexCoord")
    tex = nt.nodes.new(node_type)
    for socket, value in inputs.items():
        tex.inputs[socket].default_value = value
    nt.links.new(tc.outputs["Object"], tex.inputs["Vector"])
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (*c0, 1.0)
    ramp.color_ramp.elements[1].color = (*c1, 1.0)
    nt.links.new(tex.outputs["Fac"], ramp.inputs["Fac"])
    return ramp


def screen_material():
    """An emissive wave pattern (the picture on a small screen)."""
    mat, nt, out = C.bare_material("screen")
    ramp = ramp_texture(nt, "ShaderNodeTexWave", {"Scale": 6.0, "Distortion": 4.0}, (0.05, 0.15, 0.6), (1.0, 0.55, 0.15))
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Strength"].default_value = 3.0
    nt.links.new(ramp.outputs["Color"], em.inputs["Color"])
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def leaf_material():
    """Thin leaf: translucent and diffuse mixed, veins from a noise texture."""
    mat, nt, out = C.bare_material("leaf")
    ramp = ramp_texture(nt, "ShaderNodeTexNoise", {"Scale": 14.0, "Detail": 8.0}, (0.1, 0.3, 0.04), (0.45, 0.7, 0.15))
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    trans = nt.nodes.new("ShaderNodeBsdfTranslucent")
    nt.links.new(ramp.outputs["Color"], diffuse.inputs["Color"])
    nt.links.new(ramp.outputs["Color"], trans.inputs["Color"])
    mix = nt.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.55
    nt.links.new(diffuse.outputs["BSDF"], mix.inputs[1])
    nt.links.new(trans.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return mat


def furry_ball(center, radius):
    import bpy
    ball = C.sphere("fur_ball", center, radius, C.principled("fur_skin", (0.2, 0.12, 0.07), 0.6))
    ball.data.materials.append(hair_material())
    mod = ball.modifiers.new("fur", "PARTICLE_SYSTEM")
    ps = mod.particle_system
    ps.seed = 7
    s = ps.settings
    s.type = "HAIR"
    s.count = 6000
    s.hair_length = 0.14
    s.material = 2  # the second slot: the hair BSDF
    s.root_radius = 1.0
    s.tip_radius = 0.2
    s.radius_scale = 0.004
    s.use_hair_bspline = True
    s.render_step = 3
    s.factor_random = 0.05
    bpy.context.view_layer.update()
    return ball


def build():
    scene = C.reset_scene()
    C.set_world(scene, (0.55, 0.6, 0.7), 0.08)
    r90 = math.pi / 2

    backdrop = C.principled("backdrop", (0.7, 0.68, 0.64), roughness=0.7)
    C.plane("table", (0, 1.0, 0), (8, 6), backdrop)
    C.plane("back_wall", (0, 3.0, 2.0), (8, 4), backdrop, rotation=(r90, 0, 0))

    furry_ball((-0.85, 1.0, 0.32), 0.3)

    C.cylinder("candle", (0.15, 1.35, 0.3), 0.17, 0.6, wax_material())
    C.sphere("flame", (0.15, 1.35, 0.66), 0.025, C.emitter("flame", (1.0, 0.62, 0.25), 60.0),
             segments=16, rings=8)

    C.box("screen_frame", (1.15, 2.3, 0.8), (0.85, 0.05, 0.56),
          C.principled("frame", (0.03, 0.03, 0.035), roughness=0.3))
    C.cylinder("screen_stand", (1.15, 2.32, 0.26), 0.03, 0.52,
               C.principled("stand", (0.6, 0.6, 0.62), roughness=0.25, metallic=1.0))
    C.plane("screen", (1.15, 2.27, 0.8), (0.76, 0.47), screen_material(), rotation=(r90, 0, 0))

    leaf = leaf_material()
    C.plane("leaf_a", (0.75, 0.75, 0.35), (0.22, 0.5), leaf, rotation=(math.radians(75), 0, math.radians(-25)))
    C.plane("leaf_b", (0.55, 0.85, 0.3), (0.18, 0.42), leaf, rotation=(math.radians(65), 0, math.radians(20)))

    C.area_light("key", (-2.2, -0.6, 2.0), 1.6, 120.0, color=(1.0, 0.97, 0.92))
    C.aim(bpy_obj("key"), (-0.2, 1.1, 0.3))
    C.area_light("rim", (1.2, 2.6, 0.9), 0.25, 60.0, color=(1.0, 0.8, 0.55))
    C.aim(bpy_obj("rim"), (0.65, 0.8, 0.3))

    C.camera("camera", (0.0, -2.2, 1.1), (0.0, 1.2, 0.35), lens=40.0)
    return scene


def bpy_obj(name):
    import bpy
    return bpy.data.objects[name]


if __name__ == "__main__":
    args = C.parse_args("studio", default_size=(256, 192))
    build()
    # One BVH for every render of the process: Embree builds the hair's on several threads, not
    # always alike, and a ray grazing a strand then hits in one build and misses in another (13
    # pixels of the 16-spp file differed by up to 54% from the mean of its halves, each rendered
    # with a fresh build).
    C.render_jobs(args, "studio", persistent=True)
