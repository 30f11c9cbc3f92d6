"""Runs inside Blender (headless) for tests/blender/blender_case.py:

    blender -b --factory-startup --python-exit-code 1 --python addon_scene.py -- CASE OUT_DIR

Builds the sample room (samples/scenes) at a tiny size, enables the add-on from the staged
package ($MCRECON_ADDON_STAGE, or installs $MCRECON_ADDON_ZIP for the install_zip case), does
what CASE asks and writes OUT_DIR/result.json with what it saw; the driver checks it.
"""
import json
import os
import sys
import time

import addon_utils
import bpy

CASE, OUT = sys.argv[sys.argv.index("--") + 1:][:2]
SRC = os.environ["MCRECON_SOURCE_DIR"]
sys.path.insert(0, os.path.join(SRC, "samples", "scenes"))
import common as C  # noqa: E402

W, H = 64, 48
result = {"case": CASE}


def enable_addon():
    if CASE == "install_zip":
        bpy.ops.preferences.addon_install(filepath=os.environ["MCRECON_ADDON_ZIP"], overwrite=True)
        bpy.ops.preferences.addon_enable(module="mcrecon_addon")
        mod = sys.modules.get("mcrecon_addon")
    else:
        sys.path.insert(0, os.environ["MCRECON_ADDON_STAGE"])
        mod = addon_utils.enable("mcrecon_addon", default_set=True, handle_error=None)
    assert mod is not None, "the add-on did not enable"
    result["addon_file"] = mod.__file__
    return mod


def room_scene():
    import room
    scene = room.build()
    vl = C.configure_render(scene, W, H)
    C.set_passes(vl, False)  # the add-on chooses the passes
    scene.cycles.use_denoising = True  # the add-on must turn this off
    return scene


def written(scene):
    from mcrecon_addon import render_hooks
    return render_hooks.written_path(scene)


def render(scene, path, spp, seed, animation=False):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = path
    t0 = time.time()
    if animation:
        bpy.ops.render.render(animation=True)
    else:
        bpy.ops.render.render(write_still=True)
    return time.time() - t0


def toggles(scene):
    vl = scene.view_layers[0]
    return {"use_pass_normal": vl.use_pass_normal, "use_pass_position": vl.use_pass_position,
            "use_pass_z": vl.use_pass_z, "use_pass_vector": vl.use_pass_vector,
            "cycles.denoising_store_passes": vl.cycles.denoising_store_passes}


def case_render(filter_name):
    scene = room_scene()
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = filter_name
    result["cycles_denoising"] = scene.cycles.use_denoising
    result["noisy_seconds"] = render(scene, os.path.join(OUT, "noisy"), 16, 11)
    result["noisy"] = written(scene)
    result["message"] = mc.last_message
    img = bpy.data.images.get("mcrecon Result")
    result["result_image"] = img.filepath if img else None
    mc.enabled = False  # reference: same scene, many samples, no denoising
    result["ref_seconds"] = render(scene, os.path.join(OUT, "ref"), 256, 12345)
    result["ref"] = written(scene)


def roles(filter_name, params=None, accumulate=False):
    """The roles needs() names for these settings, required and optional."""
    import mcrecon_addon.native as native
    n = native.get().needs(filter_name, params or {}, accumulate=accumulate)
    return n["required"] + n["optional"]


def case_passes():
    scene = room_scene()
    import mcrecon_addon.native as native
    import mcrecon_addon.passes as passes
    mc = scene.mcrecon
    result["default_filter"] = mc.filter  # a new scene's, before anything is chosen
    mc.enabled = True
    result["cycles_denoising"] = scene.cycles.use_denoising
    seen = {}
    for info in [i for i in native.get().filters() if i["input"] != "deep"]:  # render-time filters
        mc.filter = info["name"]
        group = getattr(mc, "params_" + info["name"])
        from mcrecon_addon import properties as props
        defaults_ok = all(
            (abs(getattr(group, s["name"]) - s["default"]) <= 1e-6 * max(1, abs(s["default"])))
            if s["type"] == "float" else props.value_of(group, info["name"], s) == s["default"]
            for s in info["parameters"])
        seen[info["name"]] = {"toggles": toggles(scene), "defaults_ok": defaults_ok, "roles": roles(info["name"])}
    result["filters"] = seen
    # Settings other than the defaults: the toggles follow needs() of the chosen settings as
    # they change (a parameter of the chosen filter, accumulate), through the panel's properties.
    settings = {}

    def switched_on(owner, prop, label, filter_name, params=None, accumulate=False):
        """Records the toggles with owner.prop = True (needs() of the settings given), then undoes it."""
        setattr(owner, prop, True)
        settings[label] = {"toggles": toggles(scene), "roles": roles(filter_name, params, accumulate)}
        setattr(owner, prop, False)
    for name in ("box", "bilateral"):
        mc.filter = name
        settings[name] = {"toggles": toggles(scene), "roles": roles(name)}
        switched_on(getattr(mc, "params_" + name), "demodulate", name + " demodulate", name, {"demodulate": True})
    switched_on(mc, "accumulate", "bilateral accumulate", "bilateral", accumulate=True)
    mc.filter = "box"
    switched_on(mc, "accumulate", "box accumulate", "box", accumulate=True)
    result["settings"] = settings
    # The panels draw the chosen filter's parameters that have an effect (recorded by a stand-in
    # layout), the main panel only its main settings; the rest in the sub-panels.
    drawn = []

    class Layout:
        def __getattr__(self, name):
            if name == "prop":
                return lambda data, prop, **kw: drawn.append(prop)
            return lambda *a, **kw: Layout()

        def __setattr__(self, name, value):
            pass

    class Panel:
        layout = Layout()
    subs = ("MCRECON_PT_features", "MCRECON_PT_fireflies", "MCRECON_PT_foveation", "MCRECON_PT_advanced")
    for name, params in (("box", {}), ("bilateral", {}), ("bilateral", {"foveated": True, "order": "1"})):
        mc.filter = name
        group = getattr(mc, "params_" + name)
        for k, v in params.items():
            setattr(group, k, v)
        drawn.clear()
        bpy.types.MCRECON_PT_render.draw(Panel(), bpy.context)
        main = list(drawn)
        for sub in subs:
            cls = getattr(bpy.types, sub)
            if cls.poll(bpy.context):
                stand_in = type("Sub", (), {"layout": Layout(), "group": cls.group})()
                if hasattr(cls, "draw_header"):
                    cls.draw_header(stand_in, bpy.context)
                cls.draw(stand_in, bpy.context)
        key = name + ("".join(" %s=%s" % kv for kv in params.items()))
        result.setdefault("panel", {})[key] = {"main": main, "all": list(drawn),
                                               "inactive": native.get().inactive_parameters(
                                                   name, {k: (int(v) if k == "order" else v)
                                                          for k, v in params.items()})}
        for k in params:
            group.property_unset(k)
    result["role_toggles"] = {r: (o + "." if o else "") + a for r, (o, a) in passes.ROLE_TOGGLES.items()}
    # The operator does the same and reports.
    mc.filter = "box"
    bpy.ops.mcrecon.apply_passes()
    result["after_operator_box"] = toggles(scene)


def light_toggles(scene):
    import mcrecon_addon.passes as passes
    vl = scene.view_layers[0]
    return {a: getattr(vl, a) for _, a in passes.LIGHT_TOGGLES.values()}


def case_light_passes():
    """'Denoise light passes' turns the light passes on (and leaves them on when turned off);
    with 'Keep components' the render's output holds the component layers."""
    scene = room_scene()
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = "box"
    result["light_before"] = light_toggles(scene)
    mc.light_passes = True
    result["light_on"] = light_toggles(scene)
    mc.keep_components = True
    render(scene, os.path.join(OUT, "noisy"), 4, 11)
    result["noisy"] = written(scene)
    result["message"] = mc.last_message
    mc.light_passes = False
    result["light_after_off"] = light_toggles(scene)


def anim_scene(filter_name, accumulate=False):
    """The anim sample scene at test size, frames 1-4, with the add-on on."""
    import anim
    scene = anim.build()
    vl = C.configure_render(scene, W, H)
    C.set_passes(vl, False)
    scene.frame_start, scene.frame_end = 1, 4
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = filter_name
    mc.accumulate = accumulate  # switches on the passes accumulation needs (position, normal; vector)
    return scene


def render_anim(scene, name, frames):
    """Renders the animation as OUT/<name>_####.exr, denoised to OUT/<name>_den_####.exr; returns
    (seconds, renders, outputs) of `frames`."""
    scene.mcrecon.output_path = os.path.join(OUT, name + "_den_####.exr")
    seconds = render(scene, os.path.join(OUT, name + "_####"), 4, 7, animation=True)
    return (seconds, [scene.render.frame_path(frame=f) for f in frames],
            [os.path.join(OUT, name + "_den_%04d.exr" % f) for f in frames])


def case_anim():
    scene = anim_scene("bmfr")
    mc = scene.mcrecon
    result["anim_seconds"], result["renders"], result["outputs"] = render_anim(scene, "anim", range(1, 5))
    result["message"] = mc.last_message
    # Re-denoise the saved sequence with the operator.
    mc.enabled = False
    r = bpy.ops.mcrecon.denoise_files(filepath=os.path.join(OUT, "anim_####.exr"),
                                      output=os.path.join(OUT, "redo_####.exr"),
                                      frame_start=1, frame_end=4, filter="bmfr")
    result["operator"] = sorted(r)
    result["redo"] = [os.path.join(OUT, "redo_%04d.exr" % f) for f in range(1, 5)]


def case_anim_accumulate():
    """An animation render with box + accumulate, then one with a frame jump (frame_step 2), then
    the operator on frames 1-4 of the anim sample sequence (samples/data)."""
    scene = anim_scene("box", accumulate=True)
    mc = scene.mcrecon
    result["toggles"] = toggles(scene)
    _, result["renders"], result["outputs"] = render_anim(scene, "anim", range(1, 5))
    result["message"] = mc.last_message
    # Frames 1 and 3: 3 does not follow 1, so its history starts fresh.
    scene.frame_start, scene.frame_end, scene.frame_step = 1, 3, 2
    _, result["step_renders"], result["step_outputs"] = render_anim(scene, "step", (1, 3))
    result["step_message"] = mc.last_message
    scene.frame_step = 1
    # The operator takes accumulate from the scene (invoke) or as its own property.
    mc.enabled = False
    sample = os.path.join(SRC, "samples", "data", "anim", "anim_1spp_####.exr")
    r = bpy.ops.mcrecon.denoise_files(filepath=sample, output=os.path.join(OUT, "op_####.exr"),
                                      frame_start=1, frame_end=4, filter="box", accumulate=True)
    result["operator"] = sorted(r)
    result["sample"] = sample
    result["op_outputs"] = [os.path.join(OUT, "op_%04d.exr" % f) for f in range(1, 5)]


def case_errors():
    scene = room_scene()
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = "box"
    mc.extra_params = "no_such_param=3"
    render(scene, os.path.join(OUT, "badparam"), 2, 1)
    result["badparam_render"] = written(scene)
    result["badparam_message"] = mc.last_message
    mc.extra_params = ""
    mc.filter = "bmfr"
    scene.view_layers[0].use_pass_position = False  # bmfr cannot run without it
    scene.view_layers[0].use_pass_normal = False
    render(scene, os.path.join(OUT, "nopass"), 2, 1)
    result["nopass_render"] = written(scene)
    result["nopass_message"] = mc.last_message
    # PNG output: the add-on writes the passes itself (File Output node) and still denoises.
    scene.render.image_settings.file_format = "PNG"
    mc.filter = "bilateral"
    render(scene, os.path.join(OUT, "png"), 2, 1)
    result["png_render"] = written(scene)
    result["png_message"] = mc.last_message
    result["png_expected"] = os.path.splitext(result["png_render"])[0] + "_denoised.png"  # next to the render


def case_composite():
    scene = room_scene()
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = "box"
    mc.before_compositing = False  # denoise the compositor's output, by choice
    scene.use_nodes = True
    scene.render.use_compositing = True
    tree = scene.node_tree
    for n in list(tree.nodes):
        tree.nodes.remove(n)
    rl = tree.nodes.new("CompositorNodeRLayers")
    inv = tree.nodes.new("CompositorNodeInvert")
    comp = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(rl.outputs["Image"], inv.inputs["Color"])
    tree.links.new(inv.outputs["Color"], comp.inputs["Image"])
    render(scene, os.path.join(OUT, "comp"), 4, 3)
    result["render"] = written(scene)
    result["message"] = mc.last_message


def scene_state(scene):
    """Every setting the add-on may change, by name."""
    import mcrecon_addon.passes as passes
    state = {"cycles.use_denoising": scene.cycles.use_denoising, "use_nodes": scene.use_nodes,
             "render.use_compositing": scene.render.use_compositing,
             "nodes": sorted(n.name for n in scene.node_tree.nodes) if scene.node_tree else []}
    for vl in scene.view_layers:
        for owner, attr in {**passes.ROLE_TOGGLES, **passes.LIGHT_TOGGLES}.values():
            obj = getattr(vl, owner) if owner else vl
            state[vl.name + "." + (owner + "." if owner else "") + attr] = getattr(obj, attr)
    return state


def case_hygiene():
    """The user's own passes survive every filter; disabling the add-on puts everything back."""
    import mcrecon_addon.native as native
    scene = room_scene()
    vl = scene.view_layers[0]
    vl.use_pass_vector = True  # the artist's, e.g. for compositor motion blur
    vl.use_pass_emit = True
    scene.render.image_settings.file_format = "PNG"  # the add-on adds its pass-file node
    result["before"] = scene_state(scene)
    mc = scene.mcrecon
    mc.enabled = True
    kept = {}
    for info in [i for i in native.get().filters() if i["input"] != "deep"]:  # render-time filters
        mc.filter = info["name"]
        for label, prop in (("", None), (" accumulate", "accumulate"), (" light passes", "light_passes")):
            if prop:
                setattr(mc, prop, True)
            kept[info["name"] + label] = (vl.use_pass_vector, vl.use_pass_emit)
            if prop:
                setattr(mc, prop, False)
    result["user_passes_kept"] = kept
    mc.filter = "bmfr"
    result["during"] = scene_state(scene)
    import mcrecon_addon.changes as changes
    result["listed_changes"] = changes.listing(scene)
    addon_utils.disable("mcrecon_addon", default_set=True)
    result["after_disable"] = scene_state(scene)


def case_png_anim():
    """A 10-frame PNG animation: PNG outputs through the scene's view, nothing left in Blender's
    temp folder; then F12 without writing: no file written, the result packed."""
    scene = room_scene()
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    scene.render.image_settings.color_depth = "8"  # the outputs follow it (16 gives 16-bit PNGs)
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.frame_start, scene.frame_end = 1, 10
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = "box"
    tmp = bpy.app.tempdir
    result["temp_before"] = sorted(os.listdir(tmp))
    render(scene, os.path.join(OUT, "png_####"), 1, 5, animation=True)
    result["renders"] = [scene.render.frame_path(frame=f) for f in range(1, 11)]
    result["outputs"] = [os.path.splitext(p)[0] + "_denoised.png" for p in result["renders"]]
    result["temp_after"] = sorted(os.listdir(tmp))
    result["message"] = mc.last_message
    img = bpy.data.images.get("mcrecon Result")
    result["packed"] = img is not None and img.packed_file is not None
    result["fake_user"] = img is not None and img.use_fake_user
    if result["packed"]:
        with open(os.path.join(OUT, "packed_last.exr"), "wb") as f:
            f.write(img.packed_file.data)
    # F12: render without writing.
    before = sorted(os.listdir(OUT))
    scene.frame_set(3)
    bpy.ops.render.render()
    result["f12_new_files"] = sorted(set(os.listdir(OUT)) - set(before))
    result["f12_temp"] = sorted(os.listdir(tmp))
    img = bpy.data.images.get("mcrecon Result")
    result["f12_packed"] = img is not None and img.packed_file is not None
    result["f12_message"] = mc.last_message


def case_denoise_files():
    """Denoise EXR Files given one file of a sequence with a gap, no range: every frame on disk."""
    import shutil
    seq = os.path.join(OUT, "seq")
    os.makedirs(seq)
    sample = os.path.join(SRC, "samples", "data", "anim", "anim_1spp_%04d.exr")
    for f in (1, 2, 3, 4, 6):
        shutil.copyfile(sample % f, os.path.join(seq, "shot_%04d.exr" % f))
    r = bpy.ops.mcrecon.denoise_files(filepath=os.path.join(seq, "shot_0003.exr"), filter="box", accumulate=True)
    result["operator"] = sorted(r)
    result["listing"] = sorted(os.listdir(seq))
    result["seq"] = seq


def case_composite_before():
    """Issue 16 point 1: Glare and a colour grade after Render Layers apply to the denoised image."""
    import subprocess
    scene = room_scene()
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.use_nodes = True
    scene.render.use_compositing = True
    tree = scene.node_tree
    for n in list(tree.nodes):
        tree.nodes.remove(n)
    rl = tree.nodes.new("CompositorNodeRLayers")
    glare = tree.nodes.new("CompositorNodeGlare")
    glare.glare_type, glare.threshold, glare.quality = "FOG_GLOW", 0.5, "HIGH"
    grade = tree.nodes.new("CompositorNodeColorBalance")
    grade.correction_method = "LIFT_GAMMA_GAIN"
    grade.gain = (1.3, 1.0, 0.8)
    grade.gamma = (1.1, 1.0, 0.9)
    comp = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(rl.outputs["Image"], glare.inputs["Image"])
    tree.links.new(glare.outputs["Image"], grade.inputs["Image"])
    tree.links.new(grade.outputs["Image"], comp.inputs["Image"])
    mc = scene.mcrecon
    mc.enabled = True
    mc.filter = "box"
    scene.cycles.samples, scene.cycles.seed = 4, 9
    scene.render.filepath = os.path.join(OUT, "comp")
    result["operator"] = sorted(bpy.ops.mcrecon.render(write_still=True))
    result["still"] = os.path.join(OUT, "comp.exr")
    result["still_denoised"] = os.path.join(OUT, "comp_denoised.exr")
    result["message"] = mc.last_message
    result["temp_left"] = sorted(f for f in os.listdir(bpy.app.tempdir) if f.startswith("mcrecon"))
    # An animation of 3 frames: frame 1 is the still above.
    scene.frame_start, scene.frame_end = 1, 3
    scene.render.filepath = os.path.join(OUT, "anim_####")
    result["anim_operator"] = sorted(bpy.ops.mcrecon.render(animation=True))
    result["anim_denoised"] = [os.path.join(OUT, "anim_%04d_denoised.exr" % f) for f in (1, 2, 3)]
    result["anim_noisy"] = [os.path.join(OUT, "anim_%04d.exr" % f) for f in (1, 2, 3)]
    scene.frame_start = scene.frame_end = 1
    scene.frame_set(1)
    # A plain command-line render cannot run the compositor pass after its job: it says so and
    # denoises the composite instead (an output, not nothing).
    scene.render.filepath = os.path.join(OUT, "plain")
    bpy.ops.render.render(write_still=True)
    result["plain_message"] = mc.last_message
    result["plain_denoised"] = os.path.join(OUT, "plain_denoised.exr")
    # The oracle: the raw render (same seed), denoised by the CLI, through the same nodes.
    mc.enabled = False
    scene.render.use_compositing = False
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.filepath = os.path.join(OUT, "raw")
    bpy.ops.render.render(write_still=True)
    raw = os.path.join(OUT, "raw.exr")
    cli = os.environ.get("MCRECON_BIN") or os.path.join(os.path.dirname(os.environ["MCRECON_ADDON_ZIP"]), "bin",
                                                        "mcrecon")
    clean = os.path.join(OUT, "cli_denoised.exr")
    p = subprocess.run([cli, "denoise", raw, "-o", clean, "-f", "box", "--layer", "ViewLayer"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    scene.render.use_compositing = True
    scene.render.image_settings.file_format = "OPEN_EXR"
    rl.mute = True
    img = tree.nodes.new("CompositorNodeImage")
    img.image = bpy.data.images.load(clean)
    tree.links.new(img.outputs["Image"], glare.inputs["Image"])
    scene.render.filepath = os.path.join(OUT, "oracle")
    bpy.ops.render.render(write_still=True)
    result["oracle"] = os.path.join(OUT, "oracle.exr")
    result["cli_denoised"] = clean


def export_state(scene):
    """What export_deep changes and must put back."""
    r, cy, vl = scene.render, scene.cycles, scene.view_layers[0]
    return {"filepath": r.filepath, "format": r.image_settings.file_format, "depth": r.image_settings.color_depth,
            "compositing": r.use_compositing, "motion_blur": r.use_motion_blur, "samples": cy.samples,
            "offset": cy.sample_offset, "filter_width": round(cy.filter_width, 6), "adaptive": cy.use_adaptive_sampling,
            "aovs": [a.name for a in vl.aovs], "vector": vl.use_pass_vector,
            "nodes": sorted(n.name for m in bpy.data.materials if m.node_tree for n in m.node_tree.nodes)}


def case_export_deep():
    """Issue 17: the per-sample export of the dof sample scene, and oracles rendered plainly."""
    import dof
    scene = dof.build()
    C.configure_render(scene, 48, 32)
    scene.cycles.seed = 5
    scene.cycles.samples = 64
    scene.cycles.filter_width = 1.5
    scene.render.filepath = os.path.join(OUT, "user_output_")
    result["before"] = export_state(scene)
    result["op"] = sorted(bpy.ops.mcrecon.export_deep(filepath=os.path.join(OUT, "deep.exr"), samples=4))
    result["after"] = export_state(scene)
    # Oracles: the 4-spp render with the same seed and a 0.01 px filter; sample 0's Depth pass.
    vl = scene.view_layers[0]
    vl.use_pass_z = True
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.image_settings.color_depth = "32"
    scene.cycles.filter_width = 0.01
    scene.cycles.use_adaptive_sampling = False
    for spp, name in ((4, "ref4"), (1, "depth0")):
        scene.cycles.samples = spp
        scene.render.filepath = os.path.join(OUT, name)
        bpy.ops.render.render(write_still=True)
    # Motion blur: the ball moves sideways over the frame; motion comes from a blur-free render.
    ball = max((o for o in scene.objects if o.type == "MESH"), key=lambda o: -o.location.y)
    ball.location.x -= 0.3
    ball.keyframe_insert("location", frame=0)
    ball.location.x += 0.6
    ball.keyframe_insert("location", frame=2)
    scene.frame_set(1)
    scene.render.use_motion_blur = True
    scene.render.filepath = os.path.join(OUT, "user_output_")
    scene.cycles.filter_width = 1.5
    result["moving"] = ball.name
    result["before_motion"] = export_state(scene)
    result["op_motion"] = sorted(bpy.ops.mcrecon.export_deep(filepath=os.path.join(OUT, "deep_motion.exr"), samples=2))
    result["after_motion"] = export_state(scene)
    result["temp_left"] = sorted(f for f in os.listdir(bpy.app.tempdir) if f.startswith("mcrecon"))
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(OUT, "shot.blend"))  # for the batch script


def halves_state(scene):
    """What render_halves changes and must put back."""
    r, cy = scene.render, scene.cycles
    return {"filepath": r.filepath, "format": r.image_settings.file_format, "depth": r.image_settings.color_depth,
            "compositing": r.use_compositing, "samples": cy.samples, "offset": cy.sample_offset,
            "adaptive": cy.use_adaptive_sampling, "denoising": cy.use_denoising,
            "layers": [vl.use for vl in scene.view_layers]}


def case_render_halves():
    """Issue 14: the current frame as two half buffers, denoised with their variance; the oracle
    renders the same samples as one render."""
    scene = room_scene()
    mc = scene.mcrecon
    mc.enabled = True  # its render handlers must leave the halves alone
    mc.filter = "box"
    mc.last_message = ""
    scene.cycles.seed = 7
    scene.cycles.samples = 8
    scene.cycles.use_adaptive_sampling = True  # turned off for the halves, then put back
    scene.render.filepath = os.path.join(OUT, "user_output_")
    result["before"] = halves_state(scene)
    out = os.path.join(OUT, "halves.exr")
    result["op"] = sorted(bpy.ops.mcrecon.render_halves(filepath=out, keep_halves=True))
    result["after"] = halves_state(scene)
    result["message"] = mc.last_message
    result["temp_left"] = sorted(f for f in os.listdir(bpy.app.tempdir) if f.startswith("mcrecon"))
    img = bpy.data.images.get("mcrecon Result")
    result["result_image"] = img.filepath if img else None
    # An odd sample count is refused by name, before anything renders.
    scene.cycles.samples = 7
    try:
        result["odd"] = sorted(bpy.ops.mcrecon.render_halves(filepath=os.path.join(OUT, "odd.exr")))
    except RuntimeError as e:
        result["odd"] = str(e)
    scene.cycles.samples = 8
    result["odd_written"] = os.path.exists(os.path.join(OUT, "odd.exr"))
    # The oracle: the 8-spp render with the same seed, adaptive sampling off, all passes.
    mc.enabled = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = os.path.join(OUT, "full8")
    bpy.ops.render.render(write_still=True)


def case_install_zip():
    scene = bpy.context.scene
    import mcrecon_addon.native as native
    result["filters"] = native.get().filter_names()
    result["native_file"] = native.get().__file__
    result["has_settings"] = hasattr(scene, "mcrecon")
    result["panel"] = hasattr(bpy.types, "MCRECON_PT_render")
    # F3 and the compositor's Add menu find "mcrecon": entries in the Render and Add menus.
    result["menus"] = {m: sorted(f.__name__ for f in getattr(bpy.types, m)._dyn_ui_initialize()
                                 if getattr(f, "__module__", "").startswith("mcrecon_addon"))
                       for m in ("TOPBAR_MT_render", "NODE_MT_add")}


enable_addon()
{"render_box": lambda: case_render("box"), "render_bilateral": lambda: case_render("bilateral"),
 "render_auto": lambda: case_render("auto"),
 "passes": case_passes, "anim_bmfr": case_anim, "anim_accumulate": case_anim_accumulate,
 "errors": case_errors, "light_passes": case_light_passes,
 "composite": case_composite, "install_zip": case_install_zip, "hygiene": case_hygiene,
 "png_anim": case_png_anim, "denoise_files": case_denoise_files,
 "composite_before": case_composite_before, "export_deep": case_export_deep,
 "render_halves": case_render_halves}[CASE]()
with open(os.path.join(OUT, "result.json"), "w") as f:
    json.dump(result, f, indent=1)
