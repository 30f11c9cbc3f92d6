"""Shared helpers for the mcrecon sample scenes (run inside Blender 3.4, headless).

Every scene script does:

    import common
    args = common.parse_args("room", default_size=(256, 192))
    common.reset_scene()
    ... build geometry, materials, lights, camera ...
    common.render_jobs(args, scene_name="room")

and is run as

    blender -b --factory-startup --python-exit-code 1 --python room.py -- --out DIR [options]

Render settings (Debian's Blender has no denoiser, see the project notes): Cycles on the CPU,
denoising off, adaptive sampling off, fixed seed per file, compositing off, motion blur off,
multilayer OpenEXR (ZIP, half colour / float geometry), every pass the denoiser can use.

For each file written the script prints one machine-readable line on stdout:

    MCRECON_FILE {"file": "...", "spp": 16, "seed": 123, "frame": 1, "seconds": 2.1, "kind": "noisy"}

which render_samples.py turns into progress lines and the manifest.
"""

import argparse
import json
import math
import os
import sys
import time
import zlib

import bpy

# Light-path settings shared by all scenes (recorded in the manifest by the driver).
CLAMP_INDIRECT = 10.0  # Blender's default; keeps the 2048-spp references free of lone fireflies
MAX_BOUNCES = 8


# --------------------------------------------------------------------------- arguments

def _int_list(text):
    return [int(t) for t in text.split(",") if t.strip()]


def _frame_range(text):
    a, _, b = text.partition("-")
    return int(a), int(b or a)


def parse_args(scene_name, default_size, sequence=False):
    """Parse the arguments after Blender's `--`."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog=f"{scene_name}.py",
                                description=f"Build and render the '{scene_name}' sample scene.")
    p.add_argument("--out", required=True, help="output folder (files go straight into it)")
    p.add_argument("--spp", type=_int_list, default=[1, 4] if sequence else [1, 4, 16, 64],
                   help="comma-separated noisy sample counts (all passes); empty string for none")
    p.add_argument("--ref-spp", type=int, default=256 if sequence else 2048,
                   help="reference sample count (Combined only); 0 = no reference")
    p.add_argument("--ref-all-passes", action="store_true",
                   help="write every pass in the reference too (bigger files)")
    p.add_argument("--width", type=int, default=default_size[0])
    p.add_argument("--height", type=int, default=default_size[1])
    p.add_argument("--threads", type=int, default=0, help="render threads, 0 = all cores")
    p.add_argument("--halves", type=_int_list, default=[],
                   help="comma-separated spp levels also written as two half buffers "
                        "(<scene>_<spp>spp_half0/1.exr: spp/2 samples each, the level's seed, "
                        "sample offsets 0 and spp/2)")
    if sequence:
        p.add_argument("--frames", type=_frame_range, default=(1, 16),
                       help="frame range, e.g. 1-16")
    p.add_argument("--draw", type=int, default=0,
                   help="stills: another draw of the noisy renders: 0 = the sample files' seeds; N > 0 seeds "
                        "every noisy render (and its halves) differently, the reference unchanged "
                        "(files named <scene>_<spp>spp_draw<N>.exr), to test a filter on renders "
                        "it has never seen")
    p.add_argument("--save-blend", default="", help="also save the built scene to this .blend")
    args = p.parse_args(argv)
    args.sequence = sequence
    return args


def seed_for(scene_name, kind, spp, frame=0):
    """Deterministic, distinct Cycles seed per (scene, noisy/ref, spp, frame)."""
    return zlib.crc32(f"{scene_name}:{kind}:{spp}:{frame}".encode()) & 0x7FFFFFFF


# --------------------------------------------------------------------------- scene set-up

def reset_scene():
    """Delete everything from the factory start-up scene (cube, light, camera) and orphan data."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for coll in (bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras,
                 bpy.data.textures, bpy.data.images):
        for block in list(coll):
            if block.users == 0:
                coll.remove(block)
    world = bpy.context.scene.world
    if world is None:
        world = bpy.data.worlds.new("World")
        bpy.context.scene.world = world
    return bpy.context.scene


def configure_render(scene, width, height, threads=0, clamp_indirect=CLAMP_INDIRECT, persistent=False,
                     transparent=False):
    """Everything that does not change between the renders of one scene. persistent: keep one
    BVH for every render of the process (Blender's persistent data); transparent: Film >
    Transparent (the world, and a shadow catcher's floor, alpha 0)."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_compositing = False
    r.use_sequencer = False
    r.use_motion_blur = False  # with motion blur the Vector pass is dropped
    r.film_transparent = transparent
    r.use_persistent_data = persistent
    r.use_border = False
    if threads > 0:
        r.threads_mode, r.threads = "FIXED", threads
    else:
        r.threads_mode = "AUTO"
    # Reproducible headers: no date, time, host or memory stamps.
    for attr in ("use_stamp_date", "use_stamp_time", "use_stamp_render_time", "use_stamp_memory",
                 "use_stamp_hostname", "use_stamp_lens", "use_stamp_marker", "use_stamp_filename",
                 "use_stamp_sequencer_strip", "use_stamp_note"):
        if hasattr(r, attr):
            setattr(r, attr, False)
    r.use_stamp = False  # do not burn anything into the pixels
    r.use_file_extension = True
    r.use_overwrite = True

    im = r.image_settings
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.exr_codec = "ZIP"
    im.color_depth = "16"  # half colour passes; geometry passes stay float
    im.use_preview = False

    scene.view_settings.view_transform = "Standard"  # only matters for previews, EXR is linear
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0

    c = scene.cycles
    c.device = "CPU"
    c.feature_set = "SUPPORTED"
    c.use_denoising = False  # this build has no OpenImageDenoise: leaving it on writes nothing
    c.use_preview_denoising = False
    c.use_adaptive_sampling = False
    c.use_animated_seed = False
    c.sample_offset = 0
    c.time_limit = 0.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = clamp_indirect
    c.max_bounces = MAX_BOUNCES
    c.diffuse_bounces = 4
    c.glossy_bounces = 4
    c.transmission_bounces = 8
    c.transparent_max_bounces = 8
    c.volume_bounces = 0
    c.blur_glossy = 1.0
    c.pixel_filter_type = "BLACKMAN_HARRIS"
    c.filter_width = 1.5

    vl = scene.view_layers[0]
    if vl.name != "ViewLayer":
        vl.name = "ViewLayer"
    return vl


# Blender's light passes (channel names in the EXR), enabled by set_passes(light_passes=True).
# Combined = (DiffDir+DiffInd)*DiffCol + (GlossDir+GlossInd)*GlossCol
#          + (TransDir+TransInd)*TransCol + Emit + Env   (no volumes in the scenes)
LIGHT_PASSES = ["DiffDir", "DiffInd", "DiffCol", "GlossDir", "GlossInd", "GlossCol",
                "TransDir", "TransInd", "TransCol", "Emit", "Env"]


def set_passes(view_layer, all_passes, light_passes=False):
    """All passes for noisy renders; only Combined for references (unless asked otherwise).
    `light_passes` adds Blender's light passes (LIGHT_PASSES) to a render with all passes."""
    view_layer.use_pass_combined = True
    for attr in ("use_pass_z", "use_pass_normal", "use_pass_position", "use_pass_vector",
                 "use_pass_diffuse_color", "use_pass_glossy_color"):
        setattr(view_layer, attr, all_passes)
    view_layer.cycles.denoising_store_passes = all_passes
    light = all_passes and light_passes
    for comp in ("diffuse", "glossy", "transmission"):
        for part in ("direct", "indirect"):
            setattr(view_layer, f"use_pass_{comp}_{part}", light)
    view_layer.use_pass_transmission_color = light
    view_layer.use_pass_emit = light
    view_layer.use_pass_environment = light


# --------------------------------------------------------------------------- materials

def _nodes(mat):
    mat.use_nodes = True
    nt = mat.node_tree
    bsdf = nt.nodes.get("Principled BSDF")
    return nt, bsdf


def principled(name, color=(0.8, 0.8, 0.8), roughness=0.5, metallic=0.0, specular=0.5,
               emission=None, strength=0.0):
    mat = bpy.data.materials.new(name)
    nt, bsdf = _nodes(mat)
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular"].default_value = specular
    if emission is not None:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return mat


def bare_material(name):
    """A node material with nothing but its output node: (material, node tree, output)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    return mat, nt, nt.nodes.new("ShaderNodeOutputMaterial")


def single_bsdf(name, node_type, inputs):
    """A material of one GGX BSDF node (node_type) into the output; inputs: {socket: value}."""
    mat, nt, out = bare_material(name)
    node = nt.nodes.new(node_type)
    node.distribution = "GGX"
    for socket, value in inputs.items():
        node.inputs[socket].default_value = value
    nt.links.new(node.outputs["BSDF"], out.inputs["Surface"])
    return mat


def glossy_bsdf(name, color, roughness=0.1):
    """Plain Glossy BSDF (GGX). Unlike the Principled BSDF, whose GlossCol pass is always 1.0 in
    Blender 3.4, its colour shows up in the GlossCol pass."""
    return single_bsdf(name, "ShaderNodeBsdfGlossy", {"Color": (*color, 1.0), "Roughness": roughness})


def glass(name, ior=1.5, color=None):
    """Clear GGX Glass BSDF, roughness 0 (color None: the node's default white)."""
    inputs = {} if color is None else {"Color": (*color, 1.0)}
    inputs.update({"Roughness": 0.0, "IOR": ior})
    return single_bsdf(name, "ShaderNodeBsdfGlass", inputs)


def emitter(name, color=(1.0, 1.0, 1.0), strength=10.0):
    """Pure emission material (for window-like emitters)."""
    mat, nt, out = bare_material(name)
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*color, 1.0)
    em.inputs["Strength"].default_value = strength
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def _coords(nt, scale, use_object=False):
    tc = nt.nodes.new("ShaderNodeTexCoord")
    mp = nt.nodes.new("ShaderNodeMapping")
    mp.inputs["Scale"].default_value = (scale, scale, scale) if isinstance(scale, (int, float)) \
        else scale
    nt.links.new(tc.outputs["Object" if use_object else "UV"], mp.inputs["Vector"])
    return mp


def checker(name, c1, c2, scale=8.0, roughness=0.5, metallic=0.0, use_object=False):
    mat = bpy.data.materials.new(name)
    nt, bsdf = _nodes(mat)
    tex = nt.nodes.new("ShaderNodeTexChecker")
    tex.inputs["Color1"].default_value = (*c1, 1.0)
    tex.inputs["Color2"].default_value = (*c2, 1.0)
    tex.inputs["Scale"].default_value = 1.0
    mp = _coords(nt, scale, use_object)
    nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    return mat


def brick(name, c1, c2, mortar=(0.75, 0.72, 0.68), scale=4.0, roughness=0.7, use_object=False):
    mat = bpy.data.materials.new(name)
    nt, bsdf = _nodes(mat)
    tex = nt.nodes.new("ShaderNodeTexBrick")
    tex.inputs["Color1"].default_value = (*c1, 1.0)
    tex.inputs["Color2"].default_value = (*c2, 1.0)
    tex.inputs["Mortar"].default_value = (*mortar, 1.0)
    tex.inputs["Scale"].default_value = 1.0
    tex.inputs["Mortar Size"].default_value = 0.03
    mp = _coords(nt, scale, use_object)
    nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = roughness
    return mat


def noise_color(name, c1, c2, scale=6.0, detail=6.0, roughness=0.4, metallic=0.0,
                rough_variation=0.0, use_object=True):
    """Albedo (and optionally roughness) driven by fractal noise through a colour ramp."""
    mat = bpy.data.materials.new(name)
    nt, bsdf = _nodes(mat)
    tex = nt.nodes.new("ShaderNodeTexNoise")
    tex.inputs["Scale"].default_value = scale
    tex.inputs["Detail"].default_value = detail
    tex.inputs["Roughness"].default_value = 0.6
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].position = 0.35
    ramp.color_ramp.elements[0].color = (*c1, 1.0)
    ramp.color_ramp.elements[1].position = 0.65
    ramp.color_ramp.elements[1].color = (*c2, 1.0)
    mp = _coords(nt, 1.0, use_object)
    nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Fac"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Metallic"].default_value = metallic
    if rough_variation > 0.0:
        mr = nt.nodes.new("ShaderNodeMapRange")
        mr.inputs["To Min"].default_value = max(0.0, roughness - rough_variation)
        mr.inputs["To Max"].default_value = min(1.0, roughness + rough_variation)
        nt.links.new(tex.outputs["Fac"], mr.inputs["Value"])
        nt.links.new(mr.outputs["Result"], bsdf.inputs["Roughness"])
    else:
        bsdf.inputs["Roughness"].default_value = roughness
    return mat


def wave_stripes(name, c1, c2, scale=3.0, roughness=0.35, use_object=True):
    mat = bpy.data.materials.new(name)
    nt, bsdf = _nodes(mat)
    tex = nt.nodes.new("ShaderNodeTexWave")
    tex.inputs["Scale"].default_value = scale
    tex.inputs["Distortion"].default_value = 2.0
    tex.inputs["Detail"].default_value = 2.0
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (*c1, 1.0)
    ramp.color_ramp.elements[1].color = (*c2, 1.0)
    mp = _coords(nt, 1.0, use_object)
    nt.links.new(mp.outputs["Vector"], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Fac"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = roughness
    return mat


def set_world(scene, color=(0.0, 0.0, 0.0), strength=1.0):
    world = scene.world
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = strength
    return world


# --------------------------------------------------------------------------- geometry

def assign(obj, mat):
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    return obj


def box(name, center, size, mat=None, rotation=(0.0, 0.0, 0.0)):
    """Axis-aligned box (before rotation) of full extent `size`, with a generated UV map."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=center, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = size
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    _cube_project_uv(obj)
    if mat is not None:
        assign(obj, mat)
    return obj


def plane(name, center, size, mat=None, rotation=(0.0, 0.0, 0.0)):
    """Rectangle of extent size=(sx, sy) in its local XY plane, normal +Z before rotation."""
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=center, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = (size[0], size[1], 1.0)
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    # UVs in metres so texture scales are comparable between planes.
    uv = obj.data.uv_layers.active.data
    for loop in obj.data.loops:
        co = obj.data.vertices[loop.vertex_index].co
        uv[loop.index].uv = (co.x, co.y)
    if mat is not None:
        assign(obj, mat)
    return obj


def _cube_project_uv(obj):
    """Box-project UVs in metres (object space) so textures do not stretch."""
    me = obj.data
    uv = me.uv_layers.active.data
    for poly in me.polygons:
        n = poly.normal
        ax = max(range(3), key=lambda i: abs(n[i]))
        for li in poly.loop_indices:
            co = me.vertices[me.loops[li].vertex_index].co
            if ax == 0:
                uv[li].uv = (co.y, co.z)
            elif ax == 1:
                uv[li].uv = (co.x, co.z)
            else:
                uv[li].uv = (co.x, co.y)


def sphere(name, center, radius, mat=None, segments=64, rings=32, smooth=True):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings, radius=radius,
                                         location=center)
    obj = bpy.context.active_object
    obj.name = name
    if smooth:
        bpy.ops.object.shade_smooth()
    if mat is not None:
        assign(obj, mat)
    return obj


def cylinder(name, center, radius, depth, mat=None, vertices=64, rotation=(0.0, 0.0, 0.0)):
    bpy.ops.mesh.primitive_cylinder_add(vertices=vertices, radius=radius, depth=depth,
                                        location=center, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    _smooth_sides(obj)
    if mat is not None:
        assign(obj, mat)
    return obj


def _smooth_sides(obj):
    """Smooth-shade the side faces of a cylinder, keep caps flat."""
    for poly in obj.data.polygons:
        poly.use_smooth = abs(poly.normal.z) < 0.5


def torus(name, center, major, minor, mat=None, rotation=(0.0, 0.0, 0.0)):
    bpy.ops.mesh.primitive_torus_add(major_radius=major, minor_radius=minor, major_segments=64,
                                     minor_segments=24, location=center, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    if mat is not None:
        assign(obj, mat)
    return obj


def monkey(name, center, size, mat=None, rotation=(0.0, 0.0, 0.0), subdiv=2):
    bpy.ops.mesh.primitive_monkey_add(size=size, location=center, rotation=rotation)
    obj = bpy.context.active_object
    obj.name = name
    mod = obj.modifiers.new("Subdivision", "SUBSURF")
    mod.levels = mod.render_levels = subdiv
    bpy.ops.object.shade_smooth()
    if mat is not None:
        assign(obj, mat)
    return obj


def area_light(name, location, size, power, color=(1.0, 1.0, 1.0), rotation=(0.0, 0.0, 0.0),
               shape="RECTANGLE", size_y=None):
    data = bpy.data.lights.new(name, "AREA")
    data.shape = shape
    data.size = size
    if size_y is not None:
        data.size_y = size_y
    data.energy = power
    data.color = color
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    obj.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(obj)
    return obj


def point_light(name, location, radius, power, color=(1.0, 1.0, 1.0)):
    """Point lamp of `power` watts, a sphere of `radius` for soft shadows."""
    data = bpy.data.lights.new(name, "POINT")
    data.shadow_soft_size = radius
    data.energy = power
    data.color = color
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def sun_light(name, rotation, strength, angle_deg=0.5, color=(1.0, 1.0, 1.0)):
    """Sun lamp; it shines along its local -Z, so `rotation` (Euler XYZ) aims it."""
    data = bpy.data.lights.new(name, "SUN")
    data.energy = strength  # irradiance, W/m^2
    data.angle = math.radians(angle_deg)
    data.color = color
    obj = bpy.data.objects.new(name, data)
    obj.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(obj)
    return obj


def sky_world(scene, sun_elevation_deg, sun_rotation_deg, strength=1.0, sky_type="NISHITA"):
    """Procedural sky (no image) as world light; its own sun disc is off (a Sun lamp does that)."""
    world = scene.world
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes.get("Background")
    sky = nt.nodes.new("ShaderNodeTexSky")
    sky.sky_type = sky_type
    if sky_type == "NISHITA":
        sky.sun_disc = False
        sky.sun_elevation = math.radians(sun_elevation_deg)
        sky.sun_rotation = math.radians(sun_rotation_deg)
    else:
        el, rot = math.radians(sun_elevation_deg), math.radians(sun_rotation_deg)
        sky.sun_direction = (math.cos(el) * math.sin(rot), -math.cos(el) * math.cos(rot),
                             math.sin(el))
    nt.links.new(sky.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = strength
    return world


def linear_keys(obj):
    """Linear interpolation between an object's keys and linear extrapolation past them, so
    every frame, the first and the last included, has motion vectors both ways."""
    for fc in obj.animation_data.action.fcurves:
        fc.extrapolation = "LINEAR"
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"


def key_orbit(cam, target, radius, height, start_deg, step_deg, frames):
    """A camera key per frame of `frames` (first, last) on a circle of `radius` around
    `target` at `height`, aimed at it: azimuth start_deg + step_deg per frame (a key every
    frame, so the path is an arc, not a chord), linear, extrapolated."""
    tx, ty, _ = target
    for frame in range(frames[0], frames[1] + 1):
        a = math.radians(start_deg + step_deg * (frame - frames[0]))
        cam.location = (tx + radius * math.sin(a), ty - radius * math.cos(a), height)
        aim(cam, target)
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    linear_keys(cam)


def camera(name, location, look_at, lens=35.0, sensor=36.0, ortho_scale=None):
    """Perspective camera, or orthographic `ortho_scale` metres wide when that is given."""
    data = bpy.data.cameras.new(name)
    data.lens = lens
    data.sensor_width = sensor
    data.sensor_fit = "HORIZONTAL"
    data.clip_start = 0.05
    data.clip_end = 100.0
    if ortho_scale is not None:
        data.type = "ORTHO"
        data.ortho_scale = ortho_scale
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    aim(obj, look_at)
    bpy.context.scene.camera = obj
    return obj


def aim(obj, target):
    from mathutils import Vector
    d = Vector(target) - obj.location
    obj.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()


# --------------------------------------------------------------------------- rendering

def camera_info(scene):
    """Camera parameters of the current frame (written to the sidecar JSON)."""
    cam = scene.camera
    m = cam.matrix_world
    d = cam.data
    info = {
        "matrix_world": [[round(m[i][j], 7) + 0.0 for j in range(4)] for i in range(4)],
        "lens_mm": round(d.lens, 6),
        "sensor_width_mm": round(d.sensor_width, 6),
        "sensor_fit": d.sensor_fit,
        "clip_start": round(d.clip_start, 6),
        "clip_end": round(d.clip_end, 6),
        "dof": bool(d.dof.use_dof),
    }
    if d.type == "ORTHO":
        info["type"] = "ORTHO"
        info["ortho_scale"] = round(d.ortho_scale, 6)
    if d.dof.use_dof:
        info["fstop"] = round(d.dof.aperture_fstop, 6)
        info["focus_distance"] = round(d.dof.focus_distance, 6)
        info["aperture_blades"] = d.dof.aperture_blades
    return info


def _emit(record):
    print("MCRECON_FILE " + json.dumps(record), flush=True)


def _render_one(scene, view_layer, path, spp, seed, all_passes, sample_offset=0,
                light_passes=False):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.cycles.sample_offset = sample_offset
    set_passes(view_layer, all_passes, light_passes)
    scene.render.filepath = path
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    dt = time.perf_counter() - t0
    if not os.path.isfile(path):
        raise RuntimeError(f"Blender wrote no file for {path} (render failed?)")
    return dt


def render_jobs(args, scene_name, clamp_indirect=CLAMP_INDIRECT, light_passes=False, persistent=False,
                transparent=False):
    """Render the noisy levels and the reference of a still, or of every frame of a sequence.

    `light_passes`: the noisy renders (and a reference with all passes) also carry Blender's
    light passes (LIGHT_PASSES); the other scenes leave it off, so their files do not change.
    A still's level listed in args.halves is also written as two half buffers: spp/2 samples
    each with the level's own seed and sample offsets 0 and spp/2, so that their mean is the
    level's file (the same samples, split in two). `persistent`, `transparent`: configure_render."""
    scene = bpy.context.scene
    view_layer = configure_render(scene, args.width, args.height, args.threads, clamp_indirect, persistent,
                                  transparent)
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    if args.save_blend:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save_blend))

    jobs = [("noisy", spp, True) for spp in args.spp]
    if args.ref_spp > 0:
        jobs.append(("ref", args.ref_spp, args.ref_all_passes))

    if not args.sequence:
        scene.frame_set(1)
        info = {"scene": scene_name, "width": args.width, "height": args.height,
                "camera": camera_info(scene)}
        for kind, spp, all_passes in jobs:
            draw = f"_draw{args.draw}" if args.draw and kind == "noisy" else ""
            name = f"{scene_name}_{spp}spp{draw}.exr" if kind == "noisy" else f"{scene_name}_ref.exr"
            seed = seed_for(scene_name + draw, kind, spp)
            dt = _render_one(scene, view_layer, os.path.join(out, name), spp, seed, all_passes,
                             light_passes=light_passes)
            _emit({"scene": scene_name, "file": name, "kind": kind, "spp": spp, "seed": seed,
                   "frame": None, "seconds": round(dt, 3), "all_passes": all_passes})
            if kind == "noisy" and spp in args.halves:
                _render_halves(scene, view_layer, out, scene_name, spp, seed, light_passes, draw)
        _emit_info(info, clamp_indirect, light_passes)
        return

    f0, f1 = args.frames
    scene.frame_start, scene.frame_end = f0, f1
    cams = {}
    # Frame-major order so that an interrupted run still leaves complete frames.
    for frame in range(f0, f1 + 1):
        scene.frame_set(frame)
        cams[frame] = camera_info(scene)
        for kind, spp, all_passes in jobs:
            stem = f"{scene_name}_{spp}spp" if kind == "noisy" else f"{scene_name}_ref"
            name = f"{stem}_{frame:04d}.exr"
            seed = seed_for(scene_name, kind, spp, frame)
            dt = _render_one(scene, view_layer, os.path.join(out, name), spp, seed, all_passes,
                             light_passes=light_passes)
            _emit({"scene": scene_name, "file": name, "kind": kind, "spp": spp, "seed": seed,
                   "frame": frame, "seconds": round(dt, 3), "all_passes": all_passes})
    _emit_info({"scene": scene_name, "width": args.width, "height": args.height,
                "frames": [f0, f1], "fps": scene.render.fps,
                "camera": {str(k): v for k, v in cams.items()}}, clamp_indirect, light_passes)


def _render_halves(scene, view_layer, out, scene_name, spp, seed, light_passes=False, draw=""):
    if spp % 2:
        raise ValueError(f"--halves: {spp} spp cannot be split in two equal halves")
    half = spp // 2
    for i in (0, 1):
        name = f"{scene_name}_{spp}spp{draw}_half{i}.exr"
        dt = _render_one(scene, view_layer, os.path.join(out, name), half, seed, True,
                         sample_offset=i * half, light_passes=light_passes)
        _emit({"scene": scene_name, "file": name, "kind": "half", "spp": half, "of_spp": spp,
               "half": i, "sample_offset": i * half, "seed": seed, "frame": None,
               "seconds": round(dt, 3), "all_passes": True})
    scene.cycles.sample_offset = 0


def _emit_info(info, clamp_indirect, light_passes=False):
    if light_passes:
        info["light_passes"] = LIGHT_PASSES
    info["blender_version"] = bpy.app.version_string
    info["cycles"] = {"device": "CPU", "denoising": False, "adaptive_sampling": False,
                      "clamp_indirect": clamp_indirect, "max_bounces": MAX_BOUNCES,
                      "pixel_filter": "BLACKMAN_HARRIS 1.5 px",
                      "sampling_pattern": bpy.context.scene.cycles.sampling_pattern}
    print("MCRECON_INFO " + json.dumps(info), flush=True)
