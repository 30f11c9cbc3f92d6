"""After each render: read the passes from the multilayer EXR the render wrote, run the chosen
filter (on the compositor's Combined when compositing is on, else the raw Combined), write the
denoised file next to the render in the render's format (PNG/JPEG/TIFF through the scene's view
transform, look, exposure and gamma; EXR as EXR) and show it as the image "mcrecon Result",
packed into the .blend (kept with the file).

When the render's format is not OpenEXR MultiLayer, the passes come from the add-on's own File
Output node (pass_output.py): render_post denoises them into a temp EXR in Blender's temp folder
and shows it; render_write (only when the render is written: animations, write_still) turns it
into the user's output. F12 without writing leaves no file: the pass file and the temp result are
deleted once used.

One native Session per render job (render_init .. render_complete/render_cancel), so temporal
filters (bmfr) and the accumulation stage (scene.mcrecon.accumulate) see the frames of an animation
in order, with their history; a frame that does not follow the last one denoised (a frame jump,
frame_step > 1, or a frame after a failed one) starts a fresh history. Errors become console
messages and scene.mcrecon.last_message; they never stop Blender writing the render."""
import os

import bpy
from bpy.app.handlers import persistent

from . import native, pass_output, properties
from .output_paths import EXTENSIONS, frame_path, output_for_frame  # noqa: F401 (frame_path: operators)

RESULT_IMAGE = "mcrecon Result"
_job = {"session": None, "key": None, "next": None}  # next: the frame that continues the history
# Temp results: path -> {"packed": shown and packed, "released": no longer needed for the output}.
_temps = {}


def log(scene, text, error=False):
    line = ("mcrecon: ERROR: " if error else "mcrecon: ") + text
    print(line, flush=True)
    try:
        scene.mcrecon.last_message = line
    except Exception:  # read-only contexts (render thread of some builds)
        pass
    if error:
        # Also a real Blender report, in full, in the Info editor and the status bar: from the
        # main loop (handlers run in the render thread, where operators have no context).
        def report():
            try:
                bpy.ops.mcrecon.report(message=text, level='ERROR')
            except Exception:  # no window (background): the console line stands
                pass
            return None
        if bpy.app.background:
            report()
        else:
            bpy.app.timers.register(report, first_interval=0.0)


def written_path(scene):
    """The file the render just wrote. Stills (write_still) use render.filepath as it is (plus the
    extension); animations substitute #### (or append the frame): take the newer of the two."""
    r = scene.render
    still = bpy.path.abspath(r.filepath)
    ext = r.file_extension
    if r.use_file_extension and not still.lower().endswith(ext.lower()):
        still += ext
    anim = r.frame_path(frame=scene.frame_current)
    found = [p for p in (still, anim) if os.path.exists(p)]
    if not found:
        return anim
    return max(found, key=os.path.getmtime)


def render_extension(scene):
    """The denoised output's extension: the render's when mcrecon writes that format, else .exr."""
    ext = scene.render.file_extension.lower()
    return ext if ext in EXTENSIONS else ".exr"


def display_settings(scene):
    """The scene's colour management as the native module's display= for PNG/JPEG/TIFF outputs."""
    vs, ds, fmt = scene.view_settings, scene.display_settings, scene.render.image_settings
    look = "" if vs.look in ("None", "NONE") else vs.look
    prefix = vs.view_transform + " - "  # Blender may name a look after its view
    if look.startswith(prefix):
        look = look[len(prefix):]
    d = {"view": vs.view_transform, "look": look, "display": ds.display_device,
         "exposure": float(vs.exposure), "gamma": float(vs.gamma)}
    if fmt.file_format in ("PNG", "TIFF") and fmt.color_depth == "16":
        d["bit_depth"] = 16
    return d


def output_for(scene, render_path):
    mc = scene.mcrecon
    ext = render_extension(scene)
    if mc.output_path:
        # An animation: a range of frames, and Blender numbered the render's own file. Then an
        # output without '#' is numbered too (output_paths.output_for_frame), never one file
        # written over by every frame.
        frame = scene.frame_current
        animation = (scene.frame_end > scene.frame_start
                     and os.path.abspath(render_path) == os.path.abspath(scene.render.frame_path(frame=frame)))
        return output_for_frame(bpy.path.abspath(mc.output_path), frame, animation, ext)
    stem, _ = os.path.splitext(render_path)
    return stem + "_denoised" + ext


def temp_result(scene, frame):
    return os.path.join(bpy.app.tempdir or "/tmp",
                        "mcrecon_%s_result_%04d.exr" % (bpy.path.clean_name(scene.name), frame))


def _remove(path):
    try:
        os.remove(path)
    except FileNotFoundError:
        pass
    except OSError as e:
        print(f"mcrecon: could not remove temp file '{path}': {e}", flush=True)


def _settle(path, **flags):
    """Marks a temp result packed and/or released; deletes it once both hold."""
    state = _temps.get(path)
    if state is None:
        return
    state.update(flags)
    if state["packed"] and state["released"]:
        _temps.pop(path, None)
        _remove(path)


def _compositing(scene):
    r = scene.render
    tree = scene.node_tree
    return bool(r.use_compositing and scene.use_nodes and tree is not None
                and any(n.bl_idname == "CompositorNodeComposite" for n in tree.nodes))


def _session(scene):
    """The job's Session, made on the first frame (parameter errors surface here)."""
    mc = native.get()
    settings = scene.mcrecon
    params = properties.filter_params(settings, settings.filter)
    key = (settings.filter, settings.accumulate, tuple(sorted((k, str(v)) for k, v in params.items())))
    if _job["session"] is None or _job["key"] != key:
        _job.update(session=mc.Session(settings.filter, params, accumulate=settings.accumulate), key=key, next=None)
    return _job["session"]


def _show_result(path):
    """Loads `path` as the image "mcrecon Result", packed into the .blend with a fake user (kept
    when the file is saved), and shows it in image editors that show the render."""
    def load():
        img = bpy.data.images.get(RESULT_IMAGE)
        if img is not None:
            if img.packed_file is not None:
                img.unpack(method="REMOVE")
            img.filepath = path
            img.source = "FILE"
            img.reload()
        else:
            img = bpy.data.images.load(path, check_existing=False)
            img.name = RESULT_IMAGE
        img.pack()
        img.use_fake_user = True
        for window in getattr(bpy.context.window_manager, "windows", []):
            for area in window.screen.areas:
                if area.type == "IMAGE_EDITOR":
                    space = area.spaces.active
                    if space.image is not None and space.image.type == "RENDER_RESULT":
                        space.image = img
        _settle(path, packed=True)
        return None
    if bpy.app.background:
        load()
    else:  # handlers run in the render thread: touch bpy.data from the main loop
        bpy.app.timers.register(load, first_interval=0.0)


def denoise_render(scene, source, out, render_path):
    """Denoises the multilayer EXR `source` (the render itself, or the add-on's pass file) into
    `out`; render_path names the render in messages. Returns out, or None (error logged)."""
    mc = native.get()
    try:
        if not os.path.exists(source):
            log(scene, f"pass file '{source}' was not written", error=True)
            return None
        session = _session(scene)
        frame = scene.frame_current
        if session.temporal and frame != _job["next"]:
            session.reset()  # a frame jump (or the first frame): no history carried over
        _job["next"] = None  # until this frame is done
        display = None if out.lower().endswith(".exr") else display_settings(scene)
        layer = pass_output.view_layer(scene).name
        passes = {}
        if _compositing(scene):
            passes = {"colour": "Composite.Combined"}
        try:
            t = session.denoise_file(source, out, layer=layer, passes=passes,
                                     keep_components=scene.mcrecon.keep_components, display=display)
        except mc.Error as e:
            if not passes or e.kind != "missing_pass" or "Composite" not in str(e):
                raise
            log(scene, "no Composite.Combined in the render: denoising the raw Combined")
            t = session.denoise_file(source, out, layer=layer, keep_components=scene.mcrecon.keep_components,
                                     display=display)
        _job["next"] = frame + 1
        log(scene, f"{session.filter}{' (accumulated)' if session.accumulate else ''} frame {frame}: {out} "
                   f"({t['filter_ms']:.0f} ms filter, {t['total_ms']:.0f} ms total)")
        for note in session.notes():
            log(scene, note)
        return out
    except mc.Error as e:
        log(scene, f"{e} [{e.kind}]; the render itself is not affected ('{render_path}')", error=True)
    except Exception as e:  # never let the add-on break a render
        log(scene, f"{type(e).__name__}: {e}", error=True)
    return None


@persistent
def on_render_init(scene, *args):
    _job.update(session=None, key=None, next=None)
    if getattr(scene, "mcrecon", None) is not None:
        pass_output.ensure(scene)  # background / main thread; the UI sets it up on filter change


@persistent
def on_render_post(scene, *args):
    # Not MultiLayer output (or F12 without a file): denoise the add-on's own pass file into a
    # temp result; render_write makes the user's output of it when the render is written.
    if not getattr(scene, "mcrecon", None) or not pass_output.needed(scene):
        return
    frame = scene.frame_current
    source = pass_output.file_for(scene, frame)
    if source is None:
        log(scene, "the output format is not OpenEXR MultiLayer and the 'mcrecon passes' node is missing: "
                   "press 'Set Passes for Filter' (or choose the filter again) before rendering", error=True)
        return
    tmp = temp_result(scene, frame)
    try:
        out = denoise_render(scene, source, tmp, scene.render.frame_path(frame=frame))
    finally:
        _remove(source)  # the pass file is ours: never left in the temp folder
    if out is not None:
        _temps[tmp] = {"packed": False, "released": False}
        _show_result(tmp)


@persistent
def on_render_write(scene, *args):
    if not getattr(scene, "mcrecon", None) or not scene.mcrecon.enabled:
        return
    path = written_path(scene)
    if pass_output.needed(scene):
        tmp = temp_result(scene, scene.frame_current)
        if tmp not in _temps:
            return  # denoising failed in render_post (logged there)
        out = output_for(scene, path)
        mc = native.get()
        try:
            mc.convert_file(tmp, out, display=display_settings(scene))
            log(scene, f"frame {scene.frame_current}: {out}")
        except mc.Error as e:
            log(scene, f"{e} [{e.kind}]; the render itself is not affected ('{path}')", error=True)
        finally:
            _settle(tmp, released=True)
        return
    out = denoise_render(scene, path, output_for(scene, path), path)
    if out is not None:
        _show_result(out)


@persistent
def on_render_complete(scene, *args):
    _job.update(session=None, key=None, next=None)
    for tmp in list(_temps):
        _settle(tmp, released=True)


_handlers = (
    (bpy.app.handlers.render_init, on_render_init),
    (bpy.app.handlers.render_post, on_render_post),
    (bpy.app.handlers.render_write, on_render_write),
    (bpy.app.handlers.render_complete, on_render_complete),
    (bpy.app.handlers.render_cancel, on_render_complete),
)


def register():
    for lst, fn in _handlers:
        if fn not in lst:
            lst.append(fn)


def unregister():
    for lst, fn in _handlers:
        if fn in lst:
            lst.remove(fn)
