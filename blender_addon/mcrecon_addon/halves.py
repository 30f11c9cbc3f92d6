"""Two half buffers (issue 14): the current frame rendered as two renders of half the scene's
samples each, with the same seed and sample offsets 0 and N/2, so that their mean is the N-spp
render (../shared/notes/blender.md; samples/check_samples.py checks it on the sample stills), and
denoised as one render whose variance pass is their difference (mcrecon denoise --half): the
step back and the firefly rules then tell a highlight its own samples agree on from a firefly.

Every setting it changes is put back; the halves are deleted unless kept (beside the result, as
<result>_half0.exr and <result>_half1.exr)."""
import os
import shutil

import bpy

from . import native, properties, render_hooks, sub_render


def half_paths(filepath):
    stem = os.path.splitext(filepath)[0]
    return stem + "_half0.exr", stem + "_half1.exr"


def render_and_denoise(scene, filepath, keep_halves=False, progress=None, log=print):
    """Renders the current frame as two half buffers and denoises them with the add-on's filter
    and settings into `filepath` (EXR, or PNG / JPEG / TIFF through the scene's view). Returns
    {"samples", "half", "filter", "timings", "notes", "halves"}. Raises on any failure (ValueError
    for the scene's settings, the native module's Error for the denoise); the scene is put back."""
    mc = native.get()
    if scene.camera is None:
        raise ValueError("the scene has no camera")
    cy, r = scene.cycles, scene.render
    samples = int(cy.samples)
    if samples < 2 or samples % 2:
        raise ValueError(f"Render > Sampling > Max Samples is {samples}: two half buffers need an even count of 2 or more")
    filepath = bpy.path.abspath(filepath)
    halves = half_paths(filepath)
    mc.check_outputs([filepath] + (list(halves) if keep_halves else []), [])
    settings = scene.mcrecon
    session = mc.Session(settings.filter, properties.filter_params(settings, settings.filter))
    display = None if filepath.lower().endswith(".exr") else render_hooks.display_settings(scene)
    if cy.use_adaptive_sampling:
        log("render_halves: adaptive sampling off for the halves (each pixel takes all its samples)")
    with sub_render.job(scene, "render_halves", samples // 2) as (undo, layer, tmpdir):
        rendered = []
        for k in (0, 1):
            cy.sample_offset = k * (samples // 2)
            r.filepath = os.path.join(tmpdir, f"half{k}")
            bpy.ops.render.render(write_still=True, layer=layer.name)
            path = r.filepath + ".exr"
            if not os.path.isfile(path):
                raise RuntimeError(f"Blender wrote no file for half {k} ('{path}'): render failed?")
            rendered.append(path)
            log(f"render_halves: half {k + 1}/2 rendered ({samples // 2} samples, sample_offset {cy.sample_offset})")
            if progress:
                progress(k + 1, 3)
        t = session.denoise_file(rendered[0], filepath, layer=layer.name, half=rendered[1], display=display)
        if progress:
            progress(3, 3)
        if keep_halves:
            for src, dst in zip(rendered, halves):  # beside the output, maybe on another disk:
                # copied under the core's temp-name convention, then renamed (io/atomic_write.h),
                # so a kept name never holds a half-written file
                part = os.path.join(os.path.dirname(dst), f".{os.path.basename(dst)}.mcrecon-tmp.{os.getpid()}")
                try:
                    shutil.copyfile(src, part)
                    os.replace(part, dst)
                finally:
                    if os.path.exists(part):
                        os.remove(part)
        log(f"render_halves: {filepath}: {samples} samples as two halves of {samples // 2}, "
            f"{session.filter} ({t['filter_ms']:.0f} ms filter)")
        return {"samples": samples, "half": samples // 2, "filter": session.filter, "timings": t,
                "notes": list(session.notes()), "halves": list(halves) if keep_halves else []}
