"""Runs inside Blender WITH a window (under Xvfb) for tests/blender/test_gui.py:

    blender --factory-startup --python gui_smoke.py -- SCENE.blend OUT_DIR   (the scene opened first)

Turns the 3D viewport into a Properties editor on the Render tab, enables the add-on on the
sample room with bilateral, opens the Features sub-panel, renders with F12 (INVOKE, the render
window), waits for the denoised result, takes screenshots (the panel; the render window); then
adds a multiply after Render Layers and renders with F12 again (Denoise Before Compositing: the
compositor pass runs from a timer), in EXR and MultiLayer output; runs Denoise EXR Files on a
40-frame sequence and presses Esc (event_simulate: run with --enable-event-simulate); writes
OUT_DIR/gui.json with what it saw; then quits."""
import json
import os
import sys

import addon_utils
import bpy
import numpy as np

OUT = sys.argv[sys.argv.index("--") + 2]
state = {"step": 0, "waited": 0.0}
result = {}


def area_of(kind):
    """The largest area of that type, with its window."""
    found = [(a.width * a.height, w, a) for w in bpy.context.window_manager.windows
             for a in w.screen.areas if a.type == kind]
    if not found:
        return None, None
    _, window, area = max(found, key=lambda t: t[0])
    return window, area


GRADE = (0.5, 1.0, 2.0, 1.0)


def pixels(img):
    """An image's float pixels, (height, width, 4), bottom row first."""
    w, h = img.size
    a = np.empty(w * h * 4, np.float32)
    img.pixels.foreach_get(a)
    return a.reshape(h, w, 4)


def finish():
    with open(os.path.join(OUT, "gui.json"), "w") as f:
        json.dump(result, f, indent=1)
    bpy.ops.wm.quit_blender()


def tick():
    try:
        return step()
    except Exception as e:  # any failure ends the run with the reason recorded
        import traceback
        result["error"] = f"{type(e).__name__}: {e}\n{traceback.format_exc()}"
        finish()
        return None


def step():
    scene = bpy.context.scene
    if state["step"] == 0:
        sys.path.insert(0, os.environ["MCRECON_ADDON_STAGE"])
        addon_utils.enable("mcrecon_addon", default_set=True, handle_error=None)
        window, area = area_of("VIEW_3D")
        area.type = "PROPERTIES"  # its tabs exist after a redraw: the next step picks Render
        scene.mcrecon.enabled = True
        scene.mcrecon.filter = "bilateral"
        state["step"] = 1
        return 1.0
    if state["step"] == 1:
        for window in bpy.context.window_manager.windows:
            for area in window.screen.areas:
                if area.type == "PROPERTIES":
                    area.spaces.active.context = "RENDER"
        state["step"] = 10
        return 1.0
    if state["step"] == 10:
        window, area = area_of("PROPERTIES")
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.screen.screenshot_area(filepath=os.path.join(OUT, "panel.png"))
        result["panel_png"] = os.path.join(OUT, "panel.png")
        result["passes_in_use"] = __import__("mcrecon_addon.passes", fromlist=["x"]).in_use(scene)
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.render.render("INVOKE_DEFAULT", write_still=False)
        state["step"] = 2
        return 1.0
    if state["step"] == 2:
        img = bpy.data.images.get("mcrecon Result")
        if (img is None or img.packed_file is None) and state["waited"] < 90:
            state["waited"] += 1.0
            return 1.0
        result["result_packed"] = img is not None and img.packed_file is not None
        result["message"] = scene.mcrecon.last_message
        window, area = area_of("IMAGE_EDITOR")
        result["render_window_shows"] = area.spaces.active.image.name if area and area.spaces.active.image else None
        if window is not None:
            with bpy.context.temp_override(window=window, area=area):
                bpy.ops.screen.screenshot(filepath=os.path.join(OUT, "render_window.png"))
        result["files_written"] = sorted(os.listdir(OUT))
        result["status_history"] = list(__import__("mcrecon_addon.status", fromlist=["x"]).history)
        # Denoise Before Compositing from the UI (the composite pass runs from a timer): a
        # constant multiply after Render Layers must apply to the denoised image.
        np.save(os.path.join(OUT, "plain.npy"), pixels(img))
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.use_nodes = True
        scene.render.use_compositing = True
        tree = scene.node_tree
        rl = next(n for n in tree.nodes if n.bl_idname == "CompositorNodeRLayers")
        comp = next(n for n in tree.nodes if n.bl_idname == "CompositorNodeComposite")
        mul = tree.nodes.new("CompositorNodeMixRGB")
        mul.blend_type = "MULTIPLY"
        mul.inputs[2].default_value = GRADE
        tree.links.new(rl.outputs["Image"], mul.inputs[1])
        tree.links.new(mul.outputs["Image"], comp.inputs["Image"])
        scene.mcrecon.last_message = ""
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.render.render("INVOKE_DEFAULT", write_still=False)
        state["step"], state["waited"] = 3, 0.0
        return 1.0
    if state["step"] == 3:
        if "compositor ran" not in scene.mcrecon.last_message and state["waited"] < 90:
            state["waited"] += 1.0
            return 1.0
        result["composite_message"] = scene.mcrecon.last_message
        img = bpy.data.images.get("mcrecon Result")
        np.save(os.path.join(OUT, "graded.npy"), pixels(img))
        result["grade"] = list(GRADE)
        # F12 with an OpenEXR MultiLayer output (no file written: the passes come from the
        # Render Result), again before compositing.
        scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
        scene.mcrecon.last_message = ""
        window, area = area_of("IMAGE_EDITOR")
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.render.render("INVOKE_DEFAULT", write_still=False)
        state["step"], state["waited"] = 4, 0.0
        return 1.0
    if state["step"] == 4:
        if "compositor ran" not in scene.mcrecon.last_message and state["waited"] < 90:
            state["waited"] += 1.0
            return 1.0
        result["multilayer_message"] = scene.mcrecon.last_message
        np.save(os.path.join(OUT, "graded_multilayer.npy"), pixels(bpy.data.images.get("mcrecon Result")))
        result["files_after_composite"] = sorted(os.listdir(OUT))
        result["temp_left"] = sorted(f for f in os.listdir(bpy.app.tempdir) if f.startswith("mcrecon"))
        # Denoise EXR Files in the UI (modal), then Esc.
        window = bpy.context.window_manager.windows[0]
        os.makedirs(os.path.join(OUT, "seq_out"))
        with bpy.context.temp_override(window=window, screen=window.screen):
            bpy.ops.mcrecon.denoise_files("EXEC_DEFAULT", filepath=os.path.join(OUT, "seq", "seq_0001.exr"),
                                          output=os.path.join(OUT, "seq_out", "out_####.exr"), filter="box")
        state["step"] = 5
        return 0.05
    if state["step"] == 5:
        window = bpy.context.window_manager.windows[0]
        window.event_simulate(type="ESC", value="PRESS")
        result["esc_sent_at"] = len(os.listdir(os.path.join(OUT, "seq_out")))
        state["step"], state["waited"] = 6, 0.0
        return 1.0
    if state["step"] == 6:
        # Long enough for the rest of the sequence, had Esc not stopped it (about 0.1 s a frame).
        if state["waited"] < 8:
            state["waited"] += 1.0
            return 1.0
        result["seq_written"] = len(os.listdir(os.path.join(OUT, "seq_out")))
        finish()
        return None


bpy.app.timers.register(tick, first_interval=2.0)
