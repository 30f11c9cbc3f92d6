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


# The extensions mcrecon writes (io/output_format.h): EXR, or PNG/JPEG/TIFF through the view.
EXTENSIONS = (".exr", ".png", ".jpg", ".jpeg", ".tif", ".tiff")


def has_known_extension(path):
    return os.path.splitext(path)[1].lower() in EXTENSIONS


def output_for_frame(output_path, frame, animation, default_ext=".exr"):
    """The denoised file of one frame for the add-on's Output setting (an absolute path).

    '#' runs take the frame number. Without '#', an animation (more than one frame written)
    gets the frame number, 4 digits, before the extension as Blender numbers its own output
    (out.exr -> out0001.exr), so frames never overwrite each other. default_ext (the render's
    format: '.png' for a PNG render) is added when the name has no extension mcrecon writes."""
    if "#" in output_path:
        out = frame_path(output_path, frame)
    elif animation:
        stem, ext = os.path.splitext(output_path)
        if ext.lower() not in EXTENSIONS:
            stem, ext = output_path, ""
        out = stem + str(frame).zfill(4) + ext
    else:
        out = output_path
    return out if has_known_extension(out) else out + default_ext
