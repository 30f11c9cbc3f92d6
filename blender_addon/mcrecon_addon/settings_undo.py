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
