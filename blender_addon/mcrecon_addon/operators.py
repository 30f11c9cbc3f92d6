"""Operators: mcrecon.denoise_files (re-denoise saved multilayer EXR sequences, modal with Esc),
mcrecon.apply_passes (enable the chosen filter's passes, with a report), mcrecon.restore_scene."""
import os

import bpy

from . import changes, native, output_paths, pass_output, properties, status


_ITEMS = []  # Blender needs the strings of dynamic enum items kept alive


def _filter_items(self, context):
    if not _ITEMS:
        _ITEMS.extend((i["name"], i["name"], i["summary"]) for i in native.get().filters())
    return _ITEMS


class MCRECON_OT_denoise_files(bpy.types.Operator):
    """Denoise saved multilayer EXR renders: pick one file of a sequence and every frame of it found on disk is denoised in frame order (Esc stops after the current frame)"""
    bl_idname = "mcrecon.denoise_files"
    bl_label = "Denoise EXR Files"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(name="Input", subtype="FILE_PATH",
                                       description="One multilayer EXR of the sequence (or a #### pattern)")
    output: bpy.props.StringProperty(name="Output", subtype="FILE_PATH", default="",
                                     description="Output (with #### for sequences); empty: <input>_denoised.exr")
    sequence: bpy.props.BoolProperty(name="Whole Sequence", default=True,
                                     description="Denoise every frame of the picked file's sequence found on disk "
                                                 "(off: only the picked file)")
    frame_start: bpy.props.IntProperty(name="Start", default=0, min=0,
                                       description="First frame (0: the first found on disk)")
    frame_end: bpy.props.IntProperty(name="End", default=0, min=0,
                                     description="Last frame (0: the last found on disk)")
    filter: bpy.props.EnumProperty(name="Filter", items=_filter_items,
                                   description="Filter (parameters from the scene's mcrecon settings)")
    accumulate: bpy.props.BoolProperty(name="Accumulate", default=False,
                                       description="Temporal accumulation before the filter (--accumulate)")

    _timer = None

    def invoke(self, context, event):
        self.filter = context.scene.mcrecon.filter
        self.accumulate = context.scene.mcrecon.accumulate
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def _plan(self, context):
        """(jobs [(frame, input, output)], messages); raises ValueError with the reason."""
        src = bpy.path.abspath(self.filepath)
        pattern, found = output_paths.sequence_of(src) if self.sequence or "#" in src else (src, [])
        lo = self.frame_start or (found[0] if found else 0)
        hi = self.frame_end or (found[-1] if found else 0)
        frames = [f for f in found if lo <= f <= hi]
        out = bpy.path.abspath(self.output) if self.output else os.path.splitext(pattern)[0] + "_denoised.exr"
        if "#" not in pattern:
            return [(None, src, out)], []
        if not frames:
            raise ValueError(f"no frame of '{pattern}' between {lo} and {hi} on disk")
        if "#" not in out:
            raise ValueError(f"output '{out}' must contain #### for the sequence '{pattern}'")
        messages = []
        spans = output_paths.runs(frames)
        if len(spans) > 1:
            messages.append("frames missing between " + ", ".join(f"{a}-{b}" for a, b in spans) +
                            ": the history restarts after each gap")
        return [(f, output_paths.frame_path(pattern, f), output_paths.frame_path(out, f)) for f in frames], messages

    def execute(self, context):
        mc = native.get()
        try:
            self._jobs, notes = self._plan(context)
            params = properties.filter_params(context.scene.mcrecon, self.filter)
            outputs = [o for _, _, o in self._jobs]
            inputs = [i for _, i, _ in self._jobs]
            mc.check_outputs(outputs, inputs)  # nothing is filtered when one output is wrong
            self._session = mc.Session(self.filter, params, accumulate=self.accumulate)
        except (ValueError, mc.Error) as e:
            self.report({"ERROR"}, f"mcrecon: {e}" + (f" [{e.kind}]" if isinstance(e, mc.Error) else ""))
            return {"CANCELLED"}
        for m in notes:
            self.report({"WARNING"}, "mcrecon: " + m)
        self._done, self._last = 0, None
        wm = context.window_manager
        wm.progress_begin(0, len(self._jobs))
        if context.window is None or bpy.app.background:  # a script: all frames now
            while self._done < len(self._jobs):
                if not self._step(context):
                    return {"CANCELLED"}
            return self._finish(context, cancelled=False)
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _step(self, context):
        """Denoises one frame; False after an error (reported)."""
        mc = native.get()
        frame, src, out = self._jobs[self._done]
        if frame is not None and self._last is not None and frame != self._last + 1:
            self._session.reset()  # a gap: no history across it
        try:
            t = self._session.denoise_file(src, out, keep_components=context.scene.mcrecon.keep_components)
        except mc.Error as e:
            self.report({"ERROR"}, f"mcrecon: {e} [{e.kind}] ({self._done} of {len(self._jobs)} done)")
            context.window_manager.progress_end()
            return False
        self._done += 1
        self._last = frame
        context.window_manager.progress_update(self._done)
        print(f"mcrecon: [{self._done}/{len(self._jobs)}] {out} ({status.filter_text(self._session.filter, t)}, "
              f"{t['total_ms']:.0f} ms)", flush=True)
        if len(self._jobs) == 1:
            for note in t["notes"]:  # auto: its scores and choice
                self.report({"INFO"}, f"mcrecon: {note}")
        if context.area:
            context.area.header_text_set(f"mcrecon: denoised {self._done} of {len(self._jobs)} (Esc to stop)")
        return True

    def _finish(self, context, cancelled):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.area:
            context.area.header_text_set(None)
        if cancelled:
            self.report({"WARNING"}, f"mcrecon: stopped after {self._done} of {len(self._jobs)} file(s); "
                                     "every output written is complete")
            return {"CANCELLED"}
        self.report({"INFO"}, f"mcrecon: {self._done} file(s) denoised with {self.filter}")
        return {"FINISHED"}

    def modal(self, context, event):
        if event.type == "ESC":
            return self._finish(context, cancelled=True)
        if event.type == "TIMER":
            if not self._step(context):
                self._timer and context.window_manager.event_timer_remove(self._timer)
                self._timer = None
                return {"CANCELLED"}
            if self._done == len(self._jobs):
                return self._finish(context, cancelled=False)
        return {"RUNNING_MODAL"}


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


class MCRECON_OT_render(bpy.types.Operator):
    """Render, denoise, and with Denoise Before Compositing run the compositor on the denoised image (for scripts: a render handler cannot start the compositor pass)"""
    bl_idname = "mcrecon.render"
    bl_label = "Render Denoised"
    bl_options = {"REGISTER"}

    animation: bpy.props.BoolProperty(name="Animation", default=False)
    write_still: bpy.props.BoolProperty(name="Write Still", default=True)

    def execute(self, context):
        from . import composite, render_hooks
        scene = context.scene
        composite.state["operator"] = True
        try:
            if self.animation:
                bpy.ops.render.render(animation=True)
            else:
                bpy.ops.render.render(write_still=self.write_still)
            outputs = render_hooks.finish_composites(scene)
        finally:
            composite.state["operator"] = False
        for o in outputs:
            self.report({"INFO"}, f"mcrecon: {o}")
        return {"FINISHED"}


def _sub_render_job(op, context, what, total, run):
    """Runs run(progress, log), an operation of the add-on's own sub-renders, with Blender's
    progress bar; its failure becomes the operator's error report (None returned)."""
    mc = native.get()
    wm = context.window_manager
    wm.progress_begin(0, total)
    try:
        return run(lambda done, n: wm.progress_update(done), lambda m: print("mcrecon: " + m, flush=True))
    except (ValueError, RuntimeError, mc.Error) as e:
        op.report({"ERROR"}, f"mcrecon: {what}: {e}" + (f" [{e.kind}]" if isinstance(e, mc.Error) else ""))
        return None
    finally:
        wm.progress_end()


class MCRECON_OT_export_deep(bpy.types.Operator):
    """Render the current frame as K one-sample sub-renders and write them as one deep EXR for the per-sample filter sweep (depth of field, motion blur)"""
    bl_idname = "mcrecon.export_deep"
    bl_label = "Export Per-Sample EXR"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(name="Output", subtype="FILE_PATH", default="//samples.exr",
                                       description="The deep OpenEXR to write")
    samples: bpy.props.IntProperty(name="Samples", default=16, min=1, max=4096,
                                   description="Samples per pixel: one 1-spp sub-render each (sample_offset 0..K-1)")

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from . import deep_export
        total = self.samples + (1 if context.scene.render.use_motion_blur else 0)
        info = _sub_render_job(self, context, "export_deep", total, lambda progress, log: deep_export.export(
            context.scene, self.filepath, self.samples, progress=progress, log=log))
        if info is None:
            return {"CANCELLED"}
        self.report({"INFO"}, f"mcrecon: {bpy.path.abspath(self.filepath)}: {info['width']}x{info['height']}, "
                              f"{info['samples']} samples per pixel; denoise with: mcrecon denoise -f sweep")
        return {"FINISHED"}


class MCRECON_OT_render_halves(bpy.types.Operator):
    """Render the current frame as two half buffers (half the samples each, sample offsets 0 and N/2: the same samples as one render) and denoise them with the filter's variance pass from their difference"""
    bl_idname = "mcrecon.render_halves"
    bl_label = "Render Halves and Denoise"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(name="Output", subtype="FILE_PATH", default="//denoised_halves.exr",
                                       description="The denoised image (EXR, or PNG / JPEG / TIFF through the scene's view)")
    keep_halves: bpy.props.BoolProperty(name="Keep Halves", default=False,
                                        description="Keep the two half buffers beside the output (_half0.exr, _half1.exr)")

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from . import halves, render_hooks
        info = _sub_render_job(self, context, "render_halves", 3, lambda progress, log: halves.render_and_denoise(
            context.scene, self.filepath, keep_halves=self.keep_halves, progress=progress, log=log))
        if info is None:
            return {"CANCELLED"}
        out = bpy.path.abspath(self.filepath)
        render_hooks.show_result(out, now=True)
        for note in info["notes"]:
            print("mcrecon: " + note, flush=True)
        self.report({"INFO"}, f"mcrecon: {out}: {info['samples']} samples as two halves of {info['half']}, "
                              f"{status.filter_text(info['filter'], info['timings'])}")
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


_classes = (MCRECON_OT_render, MCRECON_OT_export_deep, MCRECON_OT_render_halves, MCRECON_OT_denoise_files, MCRECON_OT_apply_passes, MCRECON_OT_restore_scene, MCRECON_OT_report)


def register():
    for c in _classes:
        bpy.utils.register_class(c)


def unregister():
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
