"""fence: a wire fence and cut-out hedge leaves under a sun ("sub-pixel geometry").

Held out: never used to choose settings. A wire mesh fence (wires 1.2 cm thick, 8 cm apart,
about half a pixel wide in the image) stands 3.5 m from the camera before a cut-out hedge (planes
whose leaves are a Voronoi pattern over a Transparent BSDF: holes show what lies behind) and a
stucco wall 6 m away. A Sun lamp (0.5 degree disc) from the upper right throws the wires' and
leaves' hard shadows onto the wall and the gravel ground; a blue sky fills in. Every feature
pass (normal, depth, albedo, position) is itself aliased at the wires and leaf edges, so a
feature-guided filter sees noise in its guides at every sample count.

    blender -b --factory-startup --python-exit-code 1 --python fence.py -- --out DIR [--spp 1,4]
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def leaf_material():
    """Green leaves where a Voronoi distance is small, transparent holes elsewhere."""
    mat, nt, out = C.bare_material("hedge_leaves")
    tc = nt.nodes.new("ShaderNodeTexCoord")
    vor = nt.nodes.new("ShaderNodeTexVoronoi")
    vor.feature = "F1"
    vor.inputs["Scale"].default_value = 9.0
    nt.links.new(tc.outputs["Object"], vor.inputs["Vector"])
    cut = nt.nodes.new("ShaderNodeMath")
    cut.operation = "LESS_THAN"
    cut.inputs[1].default_value = 0.45
    nt.links.new(vor.outputs["Distance"], cut.inputs[0])
    leaf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.08, 0.22, 0.04, 1.0)
    ramp.color_ramp.elements[1].color = (0.35, 0.55, 0.12, 1.0)
    nt.links.new(vor.outputs["Color"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], leaf.inputs["Base Color"])
    leaf.inputs["Roughness"].default_value = 0.45
    holes = nt.nodes.new("ShaderNodeBsdfTransparent")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(cut.outputs["Value"], mix.inputs["Fac"])
    nt.links.new(holes.outputs["BSDF"], mix.inputs[1])
    nt.links.new(leaf.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return mat


def build():
    scene = C.reset_scene()
    C.sky_world(scene, 40.0, 150.0, strength=0.12)
    r90 = math.pi / 2

    gravel = C.noise_color("gravel", (0.35, 0.32, 0.28), (0.6, 0.56, 0.5), scale=40.0,
                           roughness=0.95)
    C.plane("ground", (0, 3, 0), (16, 14), gravel)
    stucco = C.noise_color("stucco", (0.78, 0.72, 0.62), (0.9, 0.86, 0.78), scale=8.0,
                           roughness=0.9)
    C.plane("wall", (0, 6.0, 2.0), (16, 4), stucco, rotation=(r90, 0, 0))

    leaves = leaf_material()
    for i, (x, y, z, w, h) in enumerate([(-1.6, 4.6, 1.0, 2.4, 2.0), (1.3, 4.9, 1.1, 2.8, 2.2),
                                         (-0.2, 5.3, 1.4, 3.0, 2.8)]):
        C.plane(f"hedge_{i}", (x, y, z), (w, h), leaves, rotation=(r90, 0, math.radians(8 * i - 8)))

    wire = C.principled("galvanised", (0.62, 0.63, 0.64), roughness=0.35, metallic=1.0)
    x0, x1, z0, z1, y = -2.2, 2.2, 0.0, 1.6, 2.6
    n_v = int((x1 - x0) / 0.08)
    for i in range(n_v + 1):
        x = x0 + i * 0.08
        C.cylinder(f"wire_v{i}", (x, y, (z0 + z1) / 2), 0.006, z1 - z0, wire, vertices=8)
    for j in range(int((z1 - z0) / 0.08) + 1):
        z = z0 + j * 0.08
        C.cylinder(f"wire_h{j}", (0, y, z), 0.006, x1 - x0, wire, vertices=8,
                   rotation=(0, r90, 0))
    C.cylinder("post_l", (x0 - 0.03, y, 0.9), 0.04, 1.8, wire, vertices=24)
    C.cylinder("post_r", (x1 + 0.03, y, 0.9), 0.04, 1.8, wire, vertices=24)

    el, az = math.radians(40.0), math.radians(150.0)
    C.sun_light("sun", (r90 - el, 0, az), 1.6, angle_deg=0.5, color=(1.0, 0.95, 0.86))

    C.camera("camera", (0.4, -1.0, 1.3), (0.0, 4.0, 1.0), lens=32.0)
    return scene


if __name__ == "__main__":
    args = C.parse_args("fence", default_size=(256, 192))
    build()
    C.render_jobs(args, "fence")
