"""Where the add-on writes denoised frames: pure functions (no bpy), tested from plain Python
(tests/python/test_output_guard.py). The core's output guard (io/output_guard.h) still checks
every write: never over an input, only a regular file or a new path."""
import os
import re


def frame_path(pattern, frame):
    """'#' runs become the zero-padded frame number."""
    if "#" in pattern:
        return re.sub(r"#+", lambda m: str(frame).zfill(len(m.group(0))), pattern)
    return pattern


def output_for_frame(output_path, frame, animation):
    """The denoised file of one frame for the add-on's Output setting (an absolute path).

    '#' runs take the frame number. Without '#', an animation (more than one frame written)
    gets the frame number, 4 digits, before the extension as Blender numbers its own output
    (out.exr -> out0001.exr), so frames never overwrite each other. '.exr' is added when missing."""
    if "#" in output_path:
        out = frame_path(output_path, frame)
    elif animation:
        stem, ext = os.path.splitext(output_path)
        if ext.lower() != ".exr":
            stem, ext = output_path, ""
        out = stem + str(frame).zfill(4) + ext
    else:
        out = output_path
    return out if out.lower().endswith(".exr") else out + ".exr"
