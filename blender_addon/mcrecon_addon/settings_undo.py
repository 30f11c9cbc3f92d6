"""Settings the add-on's own sub-renders change (per-sample export, half buffers), put back."""


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


def sub_renders(undo, scene, layer, samples):
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
