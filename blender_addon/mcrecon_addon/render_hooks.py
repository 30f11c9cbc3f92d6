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
import contextlib
import os

import bpy
from bpy.app.handlers import persistent

from . import composite, native, pass_output, properties, status
from .output_paths import EXTENSIONS, frame_path, output_for_frame  # noqa: F401 (frame_path: operators)

RESULT_IMAGE = "mcrecon Result"
_job = {"session": None, "key": None, "next": None, "warned_before": False, "written": False}  # next: the frame that continues the history
# Temp results: path -> {"packed": shown and packed, "released": no longer needed for the output}.
_temps = {}
_suspended = [0]  # > 0 while the add-on's own operators render (suspended())


@contextlib.contextmanager
def suspended():
    """The add-on's own sub-renders (sub_render.job) are not the user's renders: no handler
    denoises or writes them while this holds."""
    _suspended[0] += 1
    try:
        yield
    finally:
        _suspended[0] -= 1


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


def _grading(scene):
    """The compositor changes the image: its Composite node is fed by something other than a
    Render Layers node's Image (the add-on's own pass-file node and a Viewer change nothing)."""
    comp = next((n for n in scene.node_tree.nodes if n.bl_idname == "CompositorNodeComposite"), None)
    if comp is None or not comp.inputs["Image"].is_linked:
        return False
    link = comp.inputs["Image"].links[0]
    return not (link.from_node.bl_idname == "CompositorNodeRLayers" and link.from_socket.name == "Image")


def before_compositing(scene):
    """Denoise the raw Combined, then run the user's compositor on it (composite.py). A plain
    command-line render (blender -b -f/-a) cannot run the compositor pass after its own job, so
    it denoises the composite instead and says so once; bpy.ops.mcrecon.render does it right."""
    if not (scene.mcrecon.before_compositing and _compositing(scene) and _grading(scene)):
        return False
    if bpy.app.background and not composite.state["operator"]:
        if not _job.get("warned_before"):
            _job["warned_before"] = True
            log(scene, "Denoise Before Compositing needs bpy.ops.mcrecon.render() in a command-line render "
                       "(blender -b file.blend --python-expr \"import bpy; bpy.ops.mcrecon.render(animation=True)\"); "
                       "this render denoises the compositor's output")
        return False
    return True


def _session(scene):
    """The job's Session, made on the first frame (parameter errors surface here)."""
    mc = native.get()
    settings = scene.mcrecon
    params = properties.filter_params(settings, settings.filter)
    key = (settings.filter, settings.accumulate, tuple(sorted((k, str(v)) for k, v in params.items())))
    if _job["session"] is None or _job["key"] != key:
        _job.update(session=mc.Session(settings.filter, params, accumulate=settings.accumulate), key=key, next=None)
    return _job["session"]


def show_result(path, now=False):
    """Loads `path` as the image "mcrecon Result", packed into the .blend with a fake user (kept
    when the file is saved), and shows it in image editors that show the render. now: the
    caller is in the main loop already."""
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
    if bpy.app.background or now:
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
        if _compositing(scene) and not before_compositing(scene):  # "after compositing", by choice
            passes = {"colour": "Composite.Combined"}
        status.show(f"mcrecon: denoising frame {frame} with {session.filter}"
                    f"{' (accumulated)' if session.accumulate else ''}...")
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
        what = status.filter_text(session.filter, t)  # auto: what it ran
        status.show(f"mcrecon: frame {frame} denoised in {t['total_ms'] / 1000:.1f} s ({what})")
        log(scene, f"{what}{' (accumulated)' if session.accumulate else ''} frame {frame}: {out} "
                   f"({t['filter_ms']:.0f} ms filter, {t['total_ms']:.0f} ms total)")
        for note in session.notes():
            log(scene, note)
        return out
    except mc.Error as e:
        status.show(f"mcrecon: frame {scene.frame_current} not denoised (see the Info editor)")
        log(scene, f"{e} [{e.kind}]; the render itself is not affected ('{render_path}')", error=True)
    except Exception as e:  # never let the add-on break a render
        log(scene, f"{type(e).__name__}: {e}", error=True)
    return None


@persistent
def on_render_init(scene, *args):
    if _suspended[0]:
        return
    if composite.state["running"]:
        return
    _job.update(session=None, key=None, next=None, warned_before=False, written=False)
    if getattr(scene, "mcrecon", None) is not None:
        pass_output.ensure(scene)  # background / main thread; the UI sets it up on filter change


@persistent
def on_render_post(scene, *args):
    if _suspended[0]:
        return
    if composite.state["running"]:
        return
    # Not MultiLayer output (or F12 without a file): denoise the add-on's own pass file into a
    # temp result; render_write makes the user's output of it when the render is written.
    if not getattr(scene, "mcrecon", None):
        return
    if not pass_output.needed(scene):
        stale = pass_output.file_for(scene, scene.frame_current)
        if stale:  # the node outlived a switch to MultiLayer (it goes at the next UI change)
            _remove(stale)
        return
    frame = scene.frame_current
    source = pass_output.file_for(scene, frame)
    if source is None:
        log(scene, "the output format is not OpenEXR MultiLayer and the 'mcrecon passes' node is missing: "
                   "press 'Set Passes for Filter' (or choose the filter again) before rendering", error=True)
        return
    tmp = temp_result(scene, frame)
    before = before_compositing(scene)
    try:
        out = denoise_render(scene, source, tmp, scene.render.frame_path(frame=frame))
    finally:
        if not before or out is None:
            _remove(source)  # the pass file is ours: never left in the temp folder
    if out is None:
        return
    if before:  # the compositor runs on it after the job; render_write names the output
        composite.queue({"frame": frame, "denoised": tmp, "passes": source, "output": None,
                         "layer": pass_output.view_layer(scene).name, "temps": [tmp, source]})
        return
    _temps[tmp] = {"packed": False, "released": False}
    show_result(tmp)


@persistent
def on_render_write(scene, *args):
    if _suspended[0]:
        return
    if not getattr(scene, "mcrecon", None) or not scene.mcrecon.enabled:
        return
    if composite.state["running"]:
        return
    _job["written"] = True
    path = written_path(scene)
    if before_compositing(scene):
        out = output_for(scene, path)
        queued = [j for j in composite.pending() if j["frame"] == scene.frame_current]
        if queued:  # denoised in render_post from the pass file
            queued[-1]["output"] = out
            return
        if pass_output.needed(scene):
            return  # denoising failed in render_post (logged there)
        tmp = temp_result(scene, scene.frame_current)
        if denoise_render(scene, path, tmp, path) is not None:
            composite.queue({"frame": scene.frame_current, "denoised": tmp, "passes": path, "output": out,
                             "layer": pass_output.view_layer(scene).name, "temps": [tmp]})
        return
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
        show_result(out)


def finish_composites(scene):
    """Runs the queued composites (denoise before compositing) and shows the last; an F12 frame
    goes through a temp file in the render's format, packed as "mcrecon Result", then deleted."""
    def shown_path(frame):
        path = os.path.splitext(temp_result(scene, frame))[0] + "_composite" + scene.render.file_extension
        _temps[path] = {"packed": False, "released": True}
        return path
    return composite.finish(scene, log=lambda m, error=False: log(scene, m, error=error),
                            show=lambda p: show_result(p, now=True), shown_path=shown_path)


def _denoise_shown_render():
    """F12 with an OpenEXR MultiLayer output writes no file, so render_write never sees the
    passes: the Render Result (which holds them in the UI) is saved to a temp MultiLayer EXR,
    denoised, shown as "mcrecon Result", and the temp files deleted. From a timer (main loop)."""
    scene = bpy.context.scene
    img = bpy.data.images.get("Render Result")
    if img is None or not scene.mcrecon.enabled:
        return None
    frame = scene.frame_current
    tmp = temp_result(scene, frame)
    source = os.path.splitext(tmp)[0] + "_render.exr"
    try:
        img.save_render(source, scene=scene)  # the scene's format: every pass of the render
    except Exception as e:
        log(scene, f"could not read the F12 render's passes: {type(e).__name__}: {e}", error=True)
        return None
    before = before_compositing(scene)
    out = denoise_render(scene, source, tmp, "F12 render (not written)")
    _job.update(session=None, key=None, next=None)
    status.show(None)
    if out is None:
        _remove(source)
        return None
    if before:
        composite.queue({"frame": frame, "denoised": tmp, "passes": source, "output": None,
                         "layer": pass_output.view_layer(scene).name, "temps": [tmp, source]})
        finish_composites(scene)
        return None
    _remove(source)
    _temps[tmp] = {"packed": False, "released": True}
    show_result(tmp)
    return None


@persistent
def on_render_cancel(scene, *args):
    on_render_complete(scene, cancelled=True)


@persistent
def on_render_complete(scene, *args, cancelled=False):
    if _suspended[0]:
        return
    if composite.state["running"]:
        return
    f12_multilayer = (not cancelled and not bpy.app.background and not _job["written"]
                      and getattr(scene, "mcrecon", None) is not None and scene.mcrecon.enabled
                      and not pass_output.needed(scene))
    _job.update(session=None, key=None, next=None)
    status.show(None)
    for tmp in list(_temps):
        _settle(tmp, released=True)
    if composite.pending() and not composite.state["operator"]:
        if bpy.app.background:  # not reached (before_compositing is off there): never leave temps
            composite.discard()
        else:
            def later():
                finish_composites(bpy.context.scene)
                return None
            bpy.app.timers.register(later, first_interval=0.1)
    if f12_multilayer:
        bpy.app.timers.register(_denoise_shown_render, first_interval=0.1)


_handlers = (
    (bpy.app.handlers.render_init, on_render_init),
    (bpy.app.handlers.render_post, on_render_post),
    (bpy.app.handlers.render_write, on_render_write),
    (bpy.app.handlers.render_complete, on_render_complete),
    (bpy.app.handlers.render_cancel, on_render_cancel),
)


def register():
    for lst, fn in _handlers:
        if fn not in lst:
            lst.append(fn)


def unregister():
    for lst, fn in _handlers:
        if fn in lst:
            lst.remove(fn)
