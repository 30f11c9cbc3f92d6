"""Operators: mcrecon.denoise_files (re-denoise saved multilayer EXR sequences) and
mcrecon.apply_passes (enable the chosen filter's passes, with a report)."""
import os

import bpy

from . import changes, native, pass_output, properties


_ITEMS = []  # Blender needs the strings of dynamic enum items kept alive


def _filter_items(self, context):
    if not _ITEMS:
        _ITEMS.extend((i["name"], i["name"], i["summary"]) for i in native.get().filters())
    return _ITEMS


class MCRECON_OT_denoise_files(bpy.types.Operator):
    """Denoise saved multilayer EXR renders (a #### sequence, in frame order, one temporal history)"""
    bl_idname = "mcrecon.denoise_files"
    bl_label = "Denoise EXR Files"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(name="Input", subtype="FILE_PATH",
                                       description="Multilayer EXR, or a sequence pattern with ####")
    output: bpy.props.StringProperty(name="Output", subtype="FILE_PATH", default="",
                                     description="Output (with #### for sequences); empty: <input>_denoised.exr")
    frame_start: bpy.props.IntProperty(name="Start", default=1)
    frame_end: bpy.props.IntProperty(name="End", default=1)
    filter: bpy.props.EnumProperty(name="Filter", items=_filter_items,
                                   description="Filter (parameters from the scene's mcrecon settings)")
    accumulate: bpy.props.BoolProperty(name="Accumulate", default=False,
                                       description="Temporal accumulation before the filter (--accumulate)")

    def invoke(self, context, event):
        self.filter = context.scene.mcrecon.filter
        self.accumulate = context.scene.mcrecon.accumulate
        self.frame_start, self.frame_end = context.scene.frame_start, context.scene.frame_end
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        mc = native.get()
        src = bpy.path.abspath(self.filepath)
        out = bpy.path.abspath(self.output) if self.output else os.path.splitext(src)[0] + "_denoised.exr"
        seq = "#" in src
        frames = list(range(self.frame_start, self.frame_end + 1)) if seq else [None]
        if seq and "#" not in out:
            self.report({"ERROR"}, "mcrecon: output '%s' must contain #### for the sequence input '%s'" % (out, src))
            return {"CANCELLED"}
        if not frames:
            self.report({"ERROR"}, f"mcrecon: empty frame range {self.frame_start}-{self.frame_end}")
            return {"CANCELLED"}
        wm = context.window_manager
        params = properties.filter_params(context.scene.mcrecon, self.filter)
        # The core checks the outputs before any frame is filtered (never an input, every frame its
        # own regular file or new path): an error is reported, nothing is written.
        try:
            wm.progress_begin(0, len(frames))
            try:
                if seq:
                    def progress(n, total, o):
                        wm.progress_update(n)
                        print(f"mcrecon: [{n}/{total}] {o}", flush=True)
                    mc.denoise_sequence(src, out, self.frame_start, self.frame_end, self.filter, params,
                                        progress=progress, accumulate=self.accumulate,
                                        keep_components=context.scene.mcrecon.keep_components)
                else:
                    t = mc.Session(self.filter, params, accumulate=self.accumulate).denoise_file(
                        src, out, keep_components=context.scene.mcrecon.keep_components)
                    print(f"mcrecon: {out} ({t['total_ms']:.0f} ms)", flush=True)
                    for note in t["notes"]:  # auto: its scores and choice
                        self.report({"INFO"}, f"mcrecon: {note}")
            finally:
                wm.progress_end()
        except mc.Error as e:
            self.report({"ERROR"}, f"mcrecon: {e} [{e.kind}]")
            return {"CANCELLED"}
        self.report({"INFO"}, f"mcrecon: {len(frames)} file(s) denoised with {self.filter}")
        return {"FINISHED"}


class MCRECON_OT_apply_passes(bpy.types.Operator):
    """Enable exactly the passes the chosen mcrecon filter's settings need or use and turn Cycles' denoiser off"""
    bl_idname = "mcrecon.apply_passes"
    bl_label = "Set Passes for Filter"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        mc = native.get()
        try:
            messages = properties.apply_passes(context.scene)
        except mc.Error as e:
            self.report({"ERROR"}, f"mcrecon: passes not changed: {e} [{e.kind}]")
            return {"CANCELLED"}
        for m in messages:
            self.report({"INFO"}, m)
        if pass_output.ensure(context.scene, log=lambda m: self.report({"INFO"}, m)) is not None:
            self.report({"INFO"}, "mcrecon: the output format is not MultiLayer: the 'mcrecon passes' "
                                  "compositor node writes the passes")
        return {"FINISHED"}


class MCRECON_OT_restore_scene(bpy.types.Operator):
    """Put back every scene setting mcrecon changed (passes, Cycles denoising, compositing) and remove the nodes it added"""
    bl_idname = "mcrecon.restore_scene"
    bl_label = "Restore Scene Settings"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        n = changes.restore(context.scene, log=lambda m: self.report({"INFO"}, m))
        self.report({"INFO"}, f"mcrecon: {n} change(s) put back")
        return {"FINISHED"}


class MCRECON_OT_report(bpy.types.Operator):
    """Turns a message from a render handler into a Blender report (Info editor, status bar)."""
    bl_idname = "mcrecon.report"
    bl_label = "mcrecon report"
    bl_options = {'INTERNAL'}

    message: bpy.props.StringProperty()
    level: bpy.props.EnumProperty(items=[('INFO', "Info", ""), ('WARNING', "Warning", ""), ('ERROR', "Error", "")])

    def execute(self, context):
        self.report({self.level}, self.message)
        return {'FINISHED'}


_classes = (MCRECON_OT_denoise_files, MCRECON_OT_apply_passes, MCRECON_OT_restore_scene, MCRECON_OT_report)


def register():
    for c in _classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
