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


def frames_of(pattern):
    """Every frame of a '#' pattern found on disk, sorted: '####' matches 4 digits, or more
    without a leading zero (Blender writes frame 10000 of #### as 10000)."""
    folder, name = os.path.split(pattern)
    m = re.search(r"#+", name)
    if not m:
        return []
    width = len(m.group(0))
    exact = re.compile(re.escape(name[:m.start()]) + r"(\d{%d,})" % width + re.escape(name[m.end():]) + "$")
    frames = set()
    try:
        entries = os.listdir(folder or ".")
    except OSError:
        return []
    for entry in entries:
        mm = exact.match(entry)
        if mm and (len(mm.group(1)) == width or not mm.group(1).startswith("0")):
            frames.add(int(mm.group(1)))
    return sorted(frames)


def sequence_of(path):
    """The sequence a file belongs to, from the files on disk: (pattern, frames) where pattern
    has '#' for the last run of digits in the file name (as many as it has: shot_0007.exr ->
    shot_####.exr) and frames lists every frame of it found in that folder. A pattern gives its
    frames on disk; a name without digits is returned as it is with frames []."""
    folder, name = os.path.split(path)
    if "#" in name:
        return path, frames_of(path)
    stem, ext = os.path.splitext(name)
    m = re.search(r"(\d+)(?!.*\d)", stem)
    if not m:
        return path, []
    pattern = os.path.join(folder, stem[:m.start()] + "#" * len(m.group(1)) + stem[m.end():] + ext)
    return pattern, frames_of(pattern)


def runs(frames):
    """Consecutive runs of a sorted frame list: [1, 2, 3, 7, 8] -> [(1, 3), (7, 8)]."""
    out = []
    for f in frames:
        if out and f == out[-1][1] + 1:
            out[-1] = (out[-1][0], f)
        else:
            out.append((f, f))
    return out
