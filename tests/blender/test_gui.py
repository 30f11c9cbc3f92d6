"""Issue 16's GUI smoke test (ctest blender_addon_gui): Blender with a window under Xvfb opens
the sample room, shows the add-on's panel on the Render tab, renders with F12 and shows the
denoised result in the render window with progress in the status bar, then (Denoise Before
Compositing) the compositor's multiply applied to the denoised image; the panel's screenshot is kept for the README
(OUT/panel.png). Skipped (exit 77) with a message where xvfb-run is absent; setup.sh installs it.
Environment: MCRECON_BLENDER, MCRECON_SOURCE_DIR, MCRECON_ADDON_STAGE, MCRECON_TEST_TMP."""
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(os.environ["MCRECON_TEST_TMP"], "gui")
BLENDER = os.environ["MCRECON_BLENDER"]

if not shutil.which("xvfb-run"):
    print("SKIPPED: xvfb-run is not installed (apt-get install xvfb; setup.sh test installs it)")
    sys.exit(77)
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
env = dict(os.environ, BLENDER_USER_CONFIG=os.path.join(OUT, "config"),
           BLENDER_USER_SCRIPTS=os.path.join(OUT, "scripts"))
# The scene, saved headless: opening a file skips the splash screen.
blend = os.path.join(OUT, "room.blend")
build = ("import sys, os, bpy; sys.path.insert(0, os.path.join(os.environ['MCRECON_SOURCE_DIR'], 'samples', "
         "'scenes')); import common as C, room; s = room.build(); C.configure_render(s, 320, 240); "
         "s.cycles.samples = 4; s.render.image_settings.file_format = 'PNG'; s.render.filepath = os.path.join(%r, 'render'); "
         "bpy.ops.wm.save_as_mainfile(filepath=%r); "
         # A MultiLayer render, copied into a sequence for Denoise EXR Files and Esc.
         "s.render.image_settings.file_format = 'OPEN_EXR_MULTILAYER'; s.render.filepath = os.path.join(%r, 'seq_src'); "
         "bpy.ops.render.render(write_still=True)" % (OUT, blend, OUT))
p = subprocess.run([BLENDER, "-b", "--factory-startup", "--python-exit-code", "1", "--python-expr", build],
                   capture_output=True, text=True, timeout=120, env=env)
assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
SEQ = 40
os.makedirs(os.path.join(OUT, "seq"))
for f in range(1, SEQ + 1):
    shutil.copy(os.path.join(OUT, "seq_src.exr"), os.path.join(OUT, "seq", "seq_%04d.exr" % f))
try:
    p = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x2000x24", BLENDER, "--factory-startup",
                        "--enable-event-simulate", blend, "--python", os.path.join(HERE, "gui_smoke.py"), "--", blend,
                        OUT], capture_output=True, text=True, timeout=420, env=env)
    log = p.stdout + p.stderr
except subprocess.TimeoutExpired as e:  # say where it was
    out = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
    raise AssertionError("Blender with a window did not finish in 420 s; its output ends:\n" + out[-6000:])
with open(os.path.join(OUT, "blender.log"), "w") as f:
    f.write(log)
assert os.path.exists(os.path.join(OUT, "gui.json")), "Blender wrote no result:\n" + log[-4000:]
def check():
    with open(os.path.join(OUT, "gui.json")) as f:
        r = json.load(f)
    assert "error" not in r, r["error"]
    assert "Traceback" not in log, log[-4000:]
    panel = oiio.ImageBuf(r["panel_png"])
    assert panel.spec().width > 300 and panel.spec().height > 300, (panel.spec().width, panel.spec().height)
    assert r["result_packed"], "no denoised result after F12: " + r.get("message", "")
    assert "ERROR" not in r["message"], r["message"]
    assert r["render_window_shows"] == "mcrecon Result", r["render_window_shows"]
    assert [f for f in r["files_written"] if "denoised" in f] == [], f"F12 wrote files: {r['files_written']}"
    assert "Normal" in r["passes_in_use"] and "Albedo" in r["passes_in_use"], r["passes_in_use"]
    # Progress in the status bar while the render-time denoise runs.
    hist = r["status_history"]
    assert any(t.startswith("mcrecon: denoising frame 1 with bilateral") for t in hist), hist
    assert any("denoised in" in t for t in hist), hist
    # Denoise Before Compositing from the UI: the multiply applies to the denoised image (the same
    # seed renders the same samples: the plain F12 result, times the grade).
    assert "compositor ran" in r["composite_message"], r["composite_message"]
    plain, graded = np.load(os.path.join(OUT, "plain.npy")), np.load(os.path.join(OUT, "graded.npy"))
    want = plain[..., :3] * np.array(r["grade"][:3], np.float32)
    err = float(np.abs(graded[..., :3] - want).max() / max(1e-6, float(np.abs(want).max())))
    assert graded.shape == plain.shape and err < 1e-3, f"the F12 composite is not the grade of the denoised image ({err})"
    # Denoise EXR Files, modal, stopped by Esc (a simulated key press): it stops after the frame it
    # is on; every output written is complete, the rest are not started.
    outs = sorted(os.listdir(os.path.join(OUT, "seq_out")))
    assert r["esc_sent_at"] is not None, r
    assert len(outs) < SEQ, f"Esc did not stop Denoise EXR Files: {len(outs)} of {SEQ} written"
    for o in outs:
        assert o.startswith("out_") and o.endswith(".exr"), f"a partial or temp file was left: {o}"
        buf = oiio.ImageBuf(os.path.join(OUT, "seq_out", o))
        assert buf.spec().width == 320 and not buf.has_error, (o, buf.geterror())
    # F12 with a MultiLayer output (nothing written: the passes come from the Render Result).
    assert "compositor ran" in r["multilayer_message"], r["multilayer_message"]
    ml = np.load(os.path.join(OUT, "graded_multilayer.npy"))
    err_ml = float(np.abs(ml[..., :3] - want).max() / max(1e-6, float(np.abs(want).max())))
    assert ml.shape == plain.shape and err_ml < 1e-3, f"F12 with MultiLayer output: not the graded denoised image ({err_ml})"
    assert [f for f in r["files_after_composite"] if "denoised" in f or "composite" in f] == [], r["files_after_composite"]
    assert r["temp_left"] == [], r["temp_left"]
    print(f"gui: status bar showed {hist[:2]}; F12 with a multiply after Render Layers gave the grade of the "
          f"denoised image (max relative difference {err:.1e}; MultiLayer output {err_ml:.1e}); Esc stopped Denoise EXR Files after {len(outs)} of {SEQ} frames")
    print(f"gui: panel screenshot {panel.spec().width}x{panel.spec().height} ({r['panel_png']}); F12 showed "
          f"'mcrecon Result' in the render window; passes in use: {', '.join(r['passes_in_use'])}")
    print("OK")


try:
    check()
except AssertionError:
    print("blender_addon_gui failed; Blender's log ends:\n" + log[-6000:])
    raise
