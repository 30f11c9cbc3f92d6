"""The add-on's own sub-renders (the per-sample export, the half buffers): the settings they
share, put back afterwards, with the render handlers suspended and a temp folder of their own."""
import contextlib
import shutil
import tempfile

import bpy

from . import render_hooks


class Undo:
    """Settings set through it are put back in reverse order by restore()."""

    def __init__(self, what):
        self.what = what  # names the operation in a message
        self.steps = []

    def set(self, owner, attr, value):
        old = getattr(owner, attr)
        if old != value:
            self.steps.append(lambda: setattr(owner, attr, old))
            setattr(owner, attr, value)

    def keep(self, owner, attr):
        """Puts back the current value, whatever is set later."""
        old = getattr(owner, attr)
        self.steps.append(lambda: setattr(owner, attr, old))

    def add(self, undo):
        self.steps.append(undo)

    def restore(self):
        for step in reversed(self.steps):
            try:
                step()
            except Exception as e:  # keep restoring the rest
                print(f"mcrecon: {self.what}: could not restore a setting: {e}", flush=True)
        self.steps.clear()


def _settings(undo, scene, layer, samples):
    """The settings the add-on's own sub-renders share, set through `undo`: Cycles, no compositor,
    32-bit OpenEXR MultiLayer files (every pass), `samples` each without adaptive sampling (a pixel
    that stops early is not a share of one render) or Cycles' denoiser, the same seed, only `layer`;
    the output path and sample offset are the caller's to set and are put back."""
    r, cy = scene.render, scene.cycles
    undo.set(r, "engine", "CYCLES")
    undo.set(r, "use_compositing", False)
    undo.set(r, "use_file_extension", True)
    undo.set(r.image_settings, "file_format", "OPEN_EXR_MULTILAYER")
    undo.set(r.image_settings, "color_depth", "32")
    undo.keep(r, "filepath")
    undo.set(cy, "samples", samples)
    undo.set(cy, "use_adaptive_sampling", False)
    undo.set(cy, "use_denoising", False)
    undo.set(cy, "use_animated_seed", False)
    undo.keep(cy, "sample_offset")
    for vl in scene.view_layers:
        undo.set(vl, "use", vl == layer)


@contextlib.contextmanager
def job(scene, what, samples):
    """Yields (undo, layer, tmpdir) for sub-renders of `samples` samples each of the view layer
    in use, the settings above applied through `undo` and the add-on's render handlers suspended
    (these renders are not the user's: nothing denoises or writes them); on leaving, every
    setting is put back and the temp folder removed, whatever happened."""
    layer = bpy.context.view_layer if bpy.context.view_layer in scene.view_layers.values() else scene.view_layers[0]
    undo = Undo(what)
    tmpdir = tempfile.mkdtemp(prefix=f"mcrecon_{what}_", dir=bpy.app.tempdir or None)
    with render_hooks.suspended():
        try:
            _settings(undo, scene, layer, samples)
            yield undo, layer, tmpdir
        finally:
            undo.restore()
            shutil.rmtree(tmpdir, ignore_errors=True)
