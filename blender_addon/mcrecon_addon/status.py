"""What the add-on is doing, in Blender's status bar (issue 16: progress while the render-time
denoise runs). The render handlers run in the render job's thread, where the UI must not be
touched: they only set the text here; a timer in the main loop shows it in every window's status
bar and clears it when the job is over. Background renders print their lines instead."""
import bpy

_state = {"text": None, "shown": None, "timer": False}
history = []  # every text shown (tests read it)


def show(text):
    """Shows `text` (None clears) from any thread."""
    _state["text"] = text
    if text is not None:
        history.append(text)
    if bpy.app.background or _state["timer"]:
        return
    _state["timer"] = True
    bpy.app.timers.register(_tick, first_interval=0.0)


def _tick():
    text = _state["text"]
    if text != _state["shown"]:
        wm = bpy.context.window_manager
        for win in (wm.windows if wm else []):
            try:
                with bpy.context.temp_override(window=win, screen=win.screen):
                    win.workspace.status_text_set(text)
            except Exception:  # a window closing: the next tick retries
                continue
        _state["shown"] = text
    if text is None:
        _state["timer"] = False
        return None  # nothing left to show: the timer ends
    return 0.2


def filter_text(name, times):
    """'atrous', or for auto what it ran: 'auto: atrous', 'auto: kept the input', 'auto: diffuse
    atrous, glossy direct pwaf' (times: what denoise_file returned)."""
    chosen = times.get("chosen")
    if not chosen:
        return name
    if list(chosen) == ["beauty"]:
        c = chosen["beauty"]
        return f"{name}: " + ("kept the input" if c == "input" else c)
    return f"{name}: " + ", ".join(f"{stage} {c}" for stage, c in chosen.items())
