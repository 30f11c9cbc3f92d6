"""Driver of the Blender add-on tests (ctest blender_addon_CASE): runs real Blender headless on
addon_scene.py, then checks exit status, files, console messages and image error.

    /usr/bin/python3 blender_case.py CASE      (render_box, render_bilateral, passes, anim_bmfr,
                                                anim_accumulate, errors, composite, install_zip)
Environment: MCRECON_BLENDER, MCRECON_SOURCE_DIR, MCRECON_ADDON_STAGE, MCRECON_ADDON_ZIP,
MCRECON_TEST_TMP. Exit 77 = skipped (ctest SKIP_RETURN_CODE).
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np
import OpenImageIO as oiio

CASE = sys.argv[1]
HERE = os.path.dirname(os.path.abspath(__file__))
STAGE = os.environ["MCRECON_ADDON_STAGE"]
OUT = os.path.join(os.environ["MCRECON_TEST_TMP"], CASE)
sys.path.insert(0, os.path.join(STAGE, "mcrecon_addon"))
import mcrecon  # noqa: E402  (the module bundled in the add-on package)


def skip(why):
    print("SKIPPED:", why)
    sys.exit(77)


def run_blender(env_extra=None):
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    env = dict(os.environ)
    # Never touch the user's Blender configuration.
    env["BLENDER_USER_CONFIG"] = os.path.join(OUT, "config")
    env["BLENDER_USER_SCRIPTS"] = os.path.join(OUT, "scripts")
    env.update(env_extra or {})
    cmd = [os.environ["MCRECON_BLENDER"], "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", os.path.join(HERE, "addon_scene.py"), "--", CASE, OUT]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=200, env=env)
    seconds = time.time() - t0
    log = p.stdout + p.stderr
    with open(os.path.join(OUT, "blender.log"), "w") as f:
        f.write(log)
    print(f"blender {CASE}: exit {p.returncode} in {seconds:.1f} s")
    if p.returncode != 0:
        print(log[-6000:])
    assert p.returncode == 0, f"Blender exited {p.returncode}"
    assert "Traceback" not in log, "a Python traceback appeared in the console:\n" + log[-4000:]
    with open(os.path.join(OUT, "result.json")) as f:
        return json.load(f), log


def rgb(path):
    inp = oiio.ImageInput.open(path)
    assert inp, f"cannot open {path}: {oiio.geterror()}"
    names = list(inp.spec().channelnames)
    px = inp.read_image(0, 0, 0, len(names), "float")
    inp.close()
    for prefix in ("", "ViewLayer.Combined.", "Composite.Combined."):
        if all(prefix + c in names for c in "RGB"):
            return px[:, :, [names.index(prefix + c) for c in "RGB"]].astype(np.float64)
    raise AssertionError(f"{path}: no RGB channels in {names}")


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 1e-2)))


def cli():
    """This build's mcrecon CLI: $MCRECON_BIN, else bin/mcrecon beside <build>/mcrecon_addon.zip."""
    path = os.environ.get("MCRECON_BIN") or os.path.join(os.path.dirname(os.environ["MCRECON_ADDON_ZIP"]),
                                                         "bin", "mcrecon")
    assert os.access(path, os.X_OK), f"no mcrecon CLI at {path} (set MCRECON_BIN)"
    return path


def cli_denoise(src, out, filter_name, *sets, extra=()):
    """`mcrecon denoise` on a saved render, reading the view layer the add-on reads."""
    args = [cli(), "denoise", src, "-o", out, "-f", filter_name, "--layer", "ViewLayer", *extra]
    for s in sets:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, f"{' '.join(args)} exited {p.returncode}:\n{p.stderr}"
    return out


def all_channels(path):
    inp = oiio.ImageInput.open(path)
    assert inp, f"cannot open {path}: {oiio.geterror()}"
    names = list(inp.spec().channelnames)
    px = np.ascontiguousarray(inp.read_image(0, 0, 0, len(names), "float"), dtype=np.float32)
    inp.close()
    return names, px


def check_render(filter_name, box_radius=None):
    """The add-on's output is `mcrecon denoise` of the saved render with the scene's (default)
    settings, bit for bit, and closer to a 256-spp render of the same scene than the noisy one.
    With box_radius (an edge-aware filter): at least twice as close, and clearly closer than a
    plain box blur of that radius, which a filter that only blurs would not be."""
    assert filter_name in mcrecon.filter_names(), f"filter '{filter_name}' is not registered"
    r, log = run_blender()
    assert r["cycles_denoising"] is False, "the add-on did not turn Cycles denoising off"
    assert "turned off Cycles denoising" in log
    noisy, ref = r["noisy"], r["ref"]
    den = os.path.splitext(noisy)[0] + "_denoised.exr"
    for p in (noisy, ref, den):
        assert os.path.exists(p), f"missing {p}\n{log[-3000:]}"
    assert r["result_image"] and os.path.samefile(r["result_image"], den), r["result_image"]
    want = cli_denoise(noisy, os.path.join(OUT, "cli_denoised.exr"), filter_name)
    (got_names, got), (want_names, want_px) = all_channels(den), all_channels(want)
    assert got_names == want_names, (got_names, want_names)
    assert np.array_equal(got.view(np.uint32), want_px.view(np.uint32)), \
        f"the add-on's output differs from `mcrecon denoise -f {filter_name}` on the saved render " \
        f"(max |d| {np.abs(got - want_px).max()})"
    if filter_name == "auto":  # its report reaches the console, naming a filter it ran
        chose = re.findall(r"mcrecon: auto: chose (?:the )?(\S+)", log)
        # one filter, the input, or "a+b": the mean of two filters' results
        assert len(chose) == 1 and (chose[0] in mcrecon.filter_names() + ["input"] or all(
            n in mcrecon.filter_names() for n in chose[0].split("+"))), log[-3000:]
        # ... and the frame's line (the status bar's text too) names it
        shown = "kept the input" if chose[0] == "input" else chose[0]
        assert re.search(r"mcrecon: auto: %s frame \d+: " % re.escape(shown), log), log[-3000:]
        print(f"auto chose {chose[0]}")
    e_noisy, e_den = relmse(rgb(noisy), rgb(ref)), relmse(rgb(den), rgb(ref))
    print(f"{filter_name}: relMSE noisy {e_noisy:.5f}, denoised {e_den:.5f} "
          f"(render 16 spp {r['noisy_seconds']:.1f} s, reference 256 spp {r['ref_seconds']:.1f} s)")
    assert e_den < e_noisy, "the denoised render is not closer to the reference than the noisy one"
    if box_radius is not None:
        assert e_den < 0.5 * e_noisy, "the denoised render is not twice as close to the reference as the noisy one"
        blur = cli_denoise(noisy, os.path.join(OUT, "box.exr"), "box", f"radius={box_radius}")
        e_box = relmse(rgb(blur), rgb(ref))
        print(f"{filter_name}: relMSE of a box blur of radius {box_radius}: {e_box:.5f}")
        assert e_den < 0.8 * e_box, f"{filter_name} is not clearly better than a box blur of its radius"


def check_light_passes():
    """The add-on's 'Denoise light passes' enables every light pass on the view layer and its
    output (with 'Keep components') is `mcrecon denoise --set components=light_passes
    --keep-components` of the saved render bit for bit, its component layers summing to R,G,B."""
    r, log = run_blender()
    assert not any(r["light_before"].values()), r["light_before"]
    assert all(r["light_on"].values()), r["light_on"]
    # The add-on turned them on: off again when no longer needed (the user's value).
    assert not any(r["light_after_off"].values()), "light passes left on: " + str(r["light_after_off"])
    noisy = r["noisy"]
    den = os.path.splitext(noisy)[0] + "_denoised.exr"
    assert os.path.exists(den), f"missing {den}\n{log[-3000:]}"
    assert "components=light_passes" in log, log[-3000:]
    want = cli_denoise(noisy, os.path.join(OUT, "cli_denoised.exr"), "box", "components=light_passes",
                       extra=("--keep-components",))
    (got_names, got), (want_names, want_px) = all_channels(den), all_channels(want)
    assert got_names == want_names, (got_names, want_names)
    assert np.array_equal(got.view(np.uint32), want_px.view(np.uint32)), "the add-on's output differs from the CLI's"
    layers = [n for n in got_names if ".Denoised." in n and n.endswith(".R")]
    assert len(layers) == 5, got_names
    for c in "RGB":
        total = sum(got[:, :, got_names.index(n[:-1] + c)] for n in layers)
        beauty = got[:, :, got_names.index(c)]
        assert np.all(np.abs(total - beauty) <= 1e-5 * np.abs(beauty) + 1e-30), c
    print(f"light passes: {len(got_names)} channels, components sum to the beauty")


def bilateral_radius():
    """The window radius of bilateral's default settings: ceil(3 spatial_sigma)."""
    sigma = {p["name"]: p for p in mcrecon.filter_info("bilateral")["parameters"]}["spatial_sigma"]["default"]
    return int(np.ceil(3 * sigma - 1e-6))


def check_passes():
    r, log = run_blender()
    assert r["cycles_denoising"] is False
    role_toggles = r["role_toggles"]

    def on_and_wanted(f):
        return {k for k, v in f["toggles"].items() if v}, {role_toggles[x] for x in f["roles"] if x in role_toggles}
    for name, f in r["filters"].items():
        on, want = on_and_wanted(f)
        assert on == want, f"{name}: passes on {sorted(on)}, needs() says {sorted(want)}"
        assert f["defaults_ok"], f"{name}: a generated property's default differs from the table"
        print(f"{name}: {sorted(on) or 'combined only'}")
    seen = {}
    for label, f in r["settings"].items():
        on, want = on_and_wanted(f)
        assert on == want, f"{label}: passes on {sorted(on)}, needs() says {sorted(want)}"
        seen[label] = on
        print(f"{label}: {sorted(on) or 'combined only'}")
    # The settings change the passes (else the checks above would hold for a static list).
    assert seen["box"] == set() and seen["box demodulate"] == {"cycles.denoising_store_passes"}, seen
    assert {"use_pass_position", "use_pass_normal", "use_pass_vector"} <= seen["box accumulate"], seen
    assert seen["bilateral demodulate"] != seen["box"], seen
    assert "use_pass_vector" in seen["bilateral accumulate"] - seen["bilateral"], seen
    assert not any(r["filters"]["box"]["toggles"].values()), "box needs no feature pass"
    if "bilateral" in r["filters"]:
        t = r["filters"]["bilateral"]["toggles"]
        # bilateral's defaults: use_depth=off, so no depth pass (needs() drops it).
        assert t["use_pass_normal"] and t["use_pass_position"] and not t["use_pass_z"] \
            and t["cycles.denoising_store_passes"] and not t["use_pass_vector"], t
    # auto, the default: the feature passes its candidates may read (Blender renders no variance,
    # sample count or second hit), not the motion vectors no still filter reads.
    assert r["default_filter"] == "auto", r["default_filter"]
    t = r["filters"]["auto"]["toggles"]
    assert t["use_pass_normal"] and t["use_pass_position"] and t["use_pass_z"] \
        and t["cycles.denoising_store_passes"] and not t["use_pass_vector"], t
    assert not any(r["after_operator_box"].values())
    for key, d in r["panel"].items():
        name = key.split()[0]
        params = [p["name"] for p in mcrecon.filter_info(name)["parameters"] if p["name"] != "components"]
        active = [p for p in params if p not in d["inactive"]]
        assert all(p in d["all"] for p in active), f"panels for {key} lack {set(active) - set(d['all'])}"
        shown_inactive = set(d["inactive"]) & set(d["all"]) - {"foveated"}
        assert not shown_inactive, f"panels for {key} show settings with no effect: {shown_inactive}"
        assert "filter" in d["main"] and "output_path" in d["main"]
        assert len(d["main"]) <= 10, f"{key}: the main panel lists {len(d['main'])} settings: {d['main']}"
    assert "gaze_x" in r["panel"]["bilateral foveated=True order=1"]["all"]
    assert "ridge" in r["panel"]["bilateral foveated=True order=1"]["all"]
    assert "gaze_x" not in r["panel"]["bilateral"]["all"] and "ridge" not in r["panel"]["bilateral"]["all"]
    print("panels: main settings first, the rest grouped; settings without effect hidden")


def check_anim():
    if "bmfr" not in mcrecon.filter_names():
        skip("filter 'bmfr' is not registered")
    r, log = run_blender()
    for p in r["renders"] + r["outputs"] + r["redo"]:
        assert os.path.exists(p), f"missing {p}\n{log[-3000:]}"
    assert r["operator"] == ["FINISHED"], r["operator"]
    assert "ERROR" not in r["message"], r["message"]
    assert log.count("mcrecon: bmfr frame") == 4, log[-3000:]
    assert "[4/4]" in log
    # Same frames, same filter, one history each: the operator reproduces the render-time outputs.
    for a, b in zip(r["outputs"], r["redo"]):
        assert np.array_equal(rgb(a), rgb(b)), f"{a} and {b} differ"
    print(f"bmfr: 4 frames rendered and denoised in {r['anim_seconds']:.1f} s; operator matches")


def check_anim_accumulate():
    """The render hook and the operator with accumulate equal `mcrecon denoise --accumulate` of the
    same frames bit for bit, differ from the plain filter, and a frame jump starts fresh."""
    r, log = run_blender()
    for p in r["renders"] + r["outputs"] + r["step_renders"] + r["step_outputs"] + r["op_outputs"]:
        assert os.path.exists(p), f"missing {p}\n{log[-3000:]}"
    for key in ("message", "step_message"):
        assert "ERROR" not in r[key], r[key]
    assert r["toggles"]["use_pass_position"] and r["toggles"]["use_pass_normal"], r["toggles"]
    assert r["operator"] == ["FINISHED"], r["operator"]

    def same(a, b):
        (na, pa), (nb, pb) = all_channels(a), all_channels(b)
        return na == nb and np.array_equal(pa.view(np.uint32), pb.view(np.uint32))

    def sequence(renders, name, accumulate):
        """`mcrecon denoise [--accumulate] --frames 1-N` of the given renders, copied as one sequence."""
        seq = os.path.join(OUT, name)
        os.makedirs(seq, exist_ok=True)
        for n, src in enumerate(renders, 1):
            shutil.copyfile(src, os.path.join(seq, "in_%04d.exr" % n))
        out = os.path.join(seq, "out_####.exr")
        cli_denoise(os.path.join(seq, "in_####.exr"), out, "box",
                    extra=["--frames", f"1-{len(renders)}"] + (["--accumulate"] if accumulate else []))
        return [out.replace("####", "%04d" % n) for n in range(1, len(renders) + 1)]
    want = sequence(r["renders"], "cli_acc", True)
    plain = sequence(r["renders"], "cli_plain", False)
    for n, (got, w, p) in enumerate(zip(r["outputs"], want, plain), 1):
        assert same(got, w), f"render frame {n}: the add-on's output differs from `mcrecon denoise --accumulate`"
        if n > 1:
            assert not same(w, p), f"frame {n}: --accumulate gives the plain filter's pixels"
    # The jump 1 -> 3: frame 3 on its own, not frame 3 continuing frame 1's history.
    fresh = cli_denoise(r["step_renders"][1], os.path.join(OUT, "fresh_0003.exr"), "box", extra=["--accumulate"])
    continued = sequence(r["step_renders"], "cli_continued", True)[1]
    assert not same(fresh, continued), "the frame-jump check cannot tell a reset from a continued history"
    assert same(r["step_outputs"][1], fresh), "frame 3 after frame 1 kept the history: no reset on a frame jump"
    # The operator on the sample sequence.
    seq = os.path.join(OUT, "cli_sample_####.exr")
    p = subprocess.run([cli(), "denoise", r["sample"], "-o", seq, "-f", "box", "--frames", "1-4", "--accumulate"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    for n, got in enumerate(r["op_outputs"], 1):
        assert same(got, seq.replace("####", "%04d" % n)), f"operator frame {n} differs from --accumulate"
    assert log.count("mcrecon: box (accumulated) frame") == 6, log[-3000:]
    print("accumulate: render hook (4 frames), frame jump reset and operator (anim sample 1-4) match "
          "`mcrecon denoise --accumulate` bit for bit")


def check_errors():
    r, log = run_blender()
    for key, words in (("badparam", ["no_such_param"]), ("nopass", ["position"])):
        assert os.path.exists(r[key + "_render"]), f"the render was not written: {r[key + '_render']}"
        msg = r[key + "_message"]
        assert msg.startswith("mcrecon: ERROR"), f"{key}: {msg}"
        for w in words:
            assert w in msg, f"{key}: message {msg!r} does not name {w!r}"
        assert msg in log, f"{key}: message not on the console"
        print(f"{key}: {msg}")
    assert not os.path.exists(os.path.splitext(r["badparam_render"])[0] + "_denoised.exr")
    # PNG output: rendered as PNG, denoised from the add-on's own pass file.
    assert r["png_render"].endswith(".png") and os.path.exists(r["png_render"]), r["png_render"]
    assert "ERROR" not in r["png_message"] and os.path.exists(r["png_expected"]), r["png_message"]
    assert oiio.ImageInput.open(r["png_expected"]).format_name() == "png", "a PNG render gave no PNG output"
    assert "Traceback" not in log
    print(f"png: {r['png_message']}")


def check_composite():
    r, log = run_blender()
    den = os.path.splitext(r["render"])[0] + "_denoised.exr"
    assert os.path.exists(den), r["message"]
    assert "ERROR" not in r["message"], r["message"]
    inp = oiio.ImageInput.open(r["render"])
    names = list(inp.spec().channelnames)
    px = inp.read_image(0, 0, 0, len(names), "float")
    inp.close()
    comp = px[:, :, [names.index("Composite.Combined." + c) for c in "RGB"]].mean()
    raw = px[:, :, [names.index("ViewLayer.Combined." + c) for c in "RGB"]].mean()
    got = rgb(den).mean()
    print(f"composite: mean of Composite.Combined {comp:.4f}, raw Combined {raw:.4f}, denoised {got:.4f}")
    assert abs(got - comp) < 0.05 * max(1.0, abs(comp)) and abs(got - raw) > 0.1, "did not denoise the composite"


def check_hygiene():
    """Issue 16 point 2: passes the user enabled stay on whatever is chosen; disabling the add-on
    restores every setting it changed."""
    r, log = run_blender()
    lost = {k: v for k, v in r["user_passes_kept"].items() if v != [True, True]}
    assert not lost, f"the user's Vector / Emission passes were turned off by: {lost}"
    changed = {k for k in r["before"] if r["during"][k] != r["before"][k]}
    assert {"cycles.use_denoising", "use_nodes", "render.use_compositing"} <= changed, changed
    assert len(r["listed_changes"]) >= len(changed) - 1, r["listed_changes"]  # nodes: one line each
    diff = {k: (r["before"][k], r["after_disable"][k]) for k in r["before"] if r["before"][k] != r["after_disable"][k]}
    assert not diff, f"settings not restored when the add-on was disabled: {diff}"
    assert "turning mcrecon off puts it back" in log
    print(f"hygiene: user passes kept over {len(r['user_passes_kept'])} settings; {len(changed)} changed "
          f"settings restored on disable")


def check_png_anim():
    """Issue 16 point 3: no file left in Blender's temp folder after a 10-frame animation; a PNG
    render gives PNG denoised outputs (the Standard view of the denoised result); F12 writes nothing."""
    r, log = run_blender()
    assert "ERROR" not in r["message"], r["message"]
    for p in r["renders"] + r["outputs"]:
        assert os.path.exists(p), f"missing {p}\n{log[-3000:]}"
    for p in r["outputs"]:
        inp = oiio.ImageInput.open(p)
        assert inp.format_name() == "png" and inp.spec().format == "uint8", (p, inp.format_name())
        inp.close()
    left = sorted(set(r["temp_after"]) - set(r["temp_before"]))
    assert not left, f"files left in Blender's temp folder: {left}"
    assert r["packed"] and r["fake_user"], "the result is not packed with a fake user"
    # The last frame's PNG is the Standard view (the sRGB curve) of the packed denoised result.
    lin = oiio.ImageBuf(os.path.join(OUT, "packed_last.exr")).get_pixels(oiio.FLOAT).astype(np.float64)
    straight = np.clip(lin[..., :3] / np.maximum(lin[..., 3:4], 1e-30), 0, 1)
    srgb = np.where(straight <= 0.0031308, 12.92 * straight, 1.055 * straight ** (1 / 2.4) - 0.055)
    cfg = oiio.ImageSpec()
    cfg.attribute("oiio:UnassociatedAlpha", 1)
    inp = oiio.ImageInput.open(r["outputs"][-1], cfg)
    png = inp.read_image(0, 0, 0, 3, "float").astype(np.float64)
    inp.close()
    err = np.abs(png - srgb).max() * 255
    assert err <= 0.6, f"the PNG is {err:.2f} codes off the Standard view of the denoised result"  # rounding + OCIO
    assert r["f12_new_files"] == [], r["f12_new_files"]
    assert not sorted(set(r["f12_temp"]) - set(r["temp_before"])), r["f12_temp"]
    assert r["f12_packed"] and "ERROR" not in r["f12_message"], r["f12_message"]
    print(f"png_anim: 10 PNG outputs, temp folder clean, last frame within {err:.2f} codes; F12 wrote nothing")


def check_denoise_files():
    """Issue 16: one picked file gives the frames on disk (1-4 and 6, no range typed); the history
    restarts after the gap, as separate `mcrecon denoise --accumulate` runs of 1-4 and of 6 give."""
    r, log = run_blender()
    assert r["operator"] == ["FINISHED"], r["operator"] + [log[-3000:]]
    want = ["shot_%04d.exr" % f for f in (1, 2, 3, 4, 6)] + ["shot_%04d_denoised.exr" % f for f in (1, 2, 3, 4, 6)]
    assert r["listing"] == sorted(want), r["listing"]
    assert "history restarts after each gap" in log, log[-2000:]
    seq = r["seq"]
    ref = os.path.join(OUT, "ref_####.exr")
    cli_denoise(os.path.join(seq, "shot_####.exr"), ref, "box", extra=["--frames", "1-4", "--accumulate"])
    cli_denoise(os.path.join(seq, "shot_0006.exr"), os.path.join(OUT, "ref_0006.exr"), "box", extra=["--accumulate"])
    for f in (1, 2, 3, 4, 6):
        (na, pa), (nb, pb) = all_channels(os.path.join(seq, "shot_%04d_denoised.exr" % f)), \
            all_channels(os.path.join(OUT, "ref_%04d.exr" % f))
        assert na == nb and np.array_equal(pa.view(np.uint32), pb.view(np.uint32)), f"frame {f} differs from the CLI"
    print("denoise_files: frames 1-4 and 6 found from one picked file, history reset at the gap, CLI bit for bit")


def check_composite_before():
    """Issue 16 point 1: with compositing on (Glare, then a lift/gamma/gain grade after Render
    Layers), the add-on's output is those nodes applied to the denoised raw Combined: equal
    (within 1e-4) to the same nodes run on `mcrecon denoise` of the raw render, in a still and
    in frame 1 of an animation."""
    r, log = run_blender()
    assert r["operator"] == ["FINISHED"] and r["anim_operator"] == ["FINISHED"], (r["operator"], r["anim_operator"])
    assert "ERROR" not in r["message"], r["message"]
    assert r["temp_left"] == [], r["temp_left"]
    for p in [r["still"], r["still_denoised"], r["oracle"]] + r["anim_denoised"] + r["anim_noisy"]:
        assert os.path.exists(p), f"missing {p}\n{log[-3000:]}"
    got, want = rgb(r["still_denoised"]), rgb(r["oracle"])
    err = float(np.abs(got - want).max())
    print(f"composite before: max |add-on - nodes(CLI denoised)| = {err:.2e}")
    assert err <= 1e-4, f"the add-on's composited output differs from the nodes on the CLI-denoised render by {err}"
    # The nodes did something, and the noise is gone from what they graded.
    assert np.abs(got - rgb(r["cli_denoised"])).max() > 0.05, "the grade and glare were not applied"
    noisy = rgb(r["still"])
    assert np.abs(got - noisy).mean() > 1e-3, "the output is the noisy composite"
    a1 = rgb(r["anim_denoised"][0])
    assert float(np.abs(a1 - want).max()) <= 1e-4, "animation frame 1 differs from the still's oracle"
    for d, n in zip(r["anim_denoised"], r["anim_noisy"]):
        assert np.abs(rgb(d) - rgb(n)).mean() > 1e-3, f"{d} is the noisy composite"
    assert "needs bpy.ops.mcrecon.render()" in log and os.path.exists(r["plain_denoised"]), r["plain_message"]
    print("composite before: still and 3-frame animation graded after denoising; a plain "
          "command-line render says how and denoises the composite")


def read_deep(path):
    """{channel: (samples, h, w)} of a deep EXR with the same count in every pixel; its header."""
    inp = oiio.ImageInput.open(path)
    assert inp, f"cannot open {path}: {oiio.geterror()}"
    spec = inp.spec()
    assert spec.deep, f"{path} is not deep"
    dd = inp.read_native_deep_image()
    inp.close()
    names = list(spec.channelnames)
    n = {dd.samples(p) for p in range(spec.width * spec.height)}
    assert len(n) == 1, f"{path}: samples per pixel vary: {sorted(n)}"
    k = n.pop()
    out = {c: np.zeros((k, spec.height, spec.width), np.float32) for c in names}
    for p in range(spec.width * spec.height):
        y, x = divmod(p, spec.width)
        for ci, c in enumerate(names):
            for s in range(k):
                out[c][s, y, x] = dd.deep_value(p, ci, s)
    attrs = {a.name: a.value for a in spec.extra_attribs if a.name.startswith("mcrecon:")}
    return out, attrs


def check_export_deep():
    """Issue 17: bpy.ops.mcrecon.export_deep on the dof sample scene (48x32, 4 samples): the
    mean of its samples is the 4-spp render with the same seed and a 0.01 px filter, sample 0's
    depth is the 1-spp render's Depth pass, the camera is in the header, `sweep` runs on it,
    the scene is put back; with motion blur on, the moving ball has motion (mx, my)."""
    r, log = run_blender()
    assert r["op"] == ["FINISHED"] and r["op_motion"] == ["FINISHED"], (r["op"], log[-3000:])
    for a, b in (("before", "after"), ("before_motion", "after_motion")):
        changed = {k: (r[a][k], r[b][k]) for k in r[a] if r[a][k] != r[b][k]}
        assert not changed, f"export_deep left settings changed: {changed}"
    assert r["temp_left"] == [], r["temp_left"]
    deep, attrs = read_deep(os.path.join(OUT, "deep.exr"))
    assert list(deep) == ["R", "G", "B", "Z", "dx", "dy"], list(deep)
    assert deep["R"].shape == (4, 32, 48), deep["R"].shape
    for k in ("mcrecon:lens_mm", "mcrecon:fstop", "mcrecon:focus_distance", "mcrecon:sensor_width_mm"):
        assert k in attrs, (k, attrs)
    assert abs(float(attrs["mcrecon:fstop"]) - 1.2) < 1e-5 and abs(float(attrs["mcrecon:lens_mm"]) - 85) < 1e-4, attrs
    mean = np.stack([deep[c].mean(axis=0) for c in "RGB"], axis=-1)
    ref = rgb(os.path.join(OUT, "ref4.exr"))
    err = float(np.abs(mean - ref).max() / max(1e-6, float(np.abs(ref).max())))
    assert err < 1e-4, f"the samples' mean differs from the 4-spp render by {err} (relative to its maximum)"
    z0 = deep["Z"][0]
    names, px = all_channels(os.path.join(OUT, "depth0.exr"))
    depth = px[:, :, names.index("ViewLayer.Depth.Z")]
    hit = depth < 1e9
    assert hit.mean() > 0.5, hit.mean()
    zerr = float(np.abs(z0[hit] - depth[hit]).max() / depth[hit].max())
    assert zerr < 1e-4 and np.all(z0[~hit] == 0), f"sample 0's depth differs from the Depth pass: {zerr}"
    out = os.path.join(OUT, "sweep.exr")
    p = subprocess.run([cli(), "denoise", "-f", "sweep", os.path.join(OUT, "deep.exr"), "-o", out, "-v"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    got = rgb(out)
    assert np.isfinite(got).all() and np.abs(got - mean).max() > 1e-3, "sweep changed nothing"
    mdeep, mattrs = read_deep(os.path.join(OUT, "deep_motion.exr"))
    assert "mx" in mdeep and "my" in mdeep and mdeep["R"].shape[0] == 2, list(mdeep)
    moving = np.hypot(mdeep["mx"][0], mdeep["my"][0])
    assert moving.max() > 0.5 and (moving < 1e-3).mean() > 0.3, (moving.max(), (moving < 1e-3).mean())
    # The batch script, without the UI, on the saved scene.
    batch = os.path.join(OUT, "batch.exr")
    p = subprocess.run([os.environ["MCRECON_BLENDER"], "-b", "--factory-startup", os.path.join(OUT, "shot.blend"),
                        "--python", os.path.join(os.path.dirname(HERE), "..", "blender_addon", "export_deep_batch.py"),
                        "--", batch, "--samples", "2", "--frame", "1", "--addon-dir", STAGE],
                       capture_output=True, text=True, timeout=200,
                       env=dict(os.environ, BLENDER_USER_CONFIG=os.path.join(OUT, "config"),
                                BLENDER_USER_SCRIPTS=os.path.join(OUT, "scripts")))
    assert p.returncode == 0 and os.path.exists(batch), p.stdout[-2000:] + p.stderr[-2000:]
    assert read_deep(batch)[0]["R"].shape[0] == 2
    print(f"export_deep: 48x32x4 samples, mean vs the 4-spp render {err:.1e}, sample 0 depth vs the Depth pass "
          f"{zerr:.1e}, motion up to {moving.max():.2f} px on the moving ball; settings put back")


def check_render_halves():
    """Issue 14: bpy.ops.mcrecon.render_halves on the room at 64x48, 8 samples: the mean of its two
    halves is the 8-spp render with the same seed, its result is `mcrecon denoise half0 --half
    half1` bit for bit, the scene is put back (adaptive sampling included), no temp file is left,
    the render handlers left the halves alone, an odd sample count is refused by name."""
    r, log = run_blender()
    assert r["op"] == ["FINISHED"], (r["op"], log[-3000:])
    changed = {k: (r["before"][k], r["after"][k]) for k in r["before"] if r["before"][k] != r["after"][k]}
    assert not changed, f"render_halves left settings changed: {changed}"
    assert r["temp_left"] == [], r["temp_left"]
    assert r["message"] == "", f"a render handler ran on a half: {r['message']}"
    assert r["result_image"] and os.path.samefile(r["result_image"], os.path.join(OUT, "halves.exr")), r["result_image"]
    assert "7" in r["odd"] and "even" in r["odd"] and not r["odd_written"], r["odd"]
    h0, h1 = (os.path.join(OUT, f"halves_half{k}.exr") for k in (0, 1))
    mean = (rgb(h0) + rgb(h1)) / 2
    full = rgb(os.path.join(OUT, "full8.exr"))
    err = float(np.abs(mean - full).max() / max(1e-6, float(np.abs(full).max())))
    assert err < 1e-4, f"the halves' mean differs from the 8-spp render by {err} (relative to its maximum)"
    cli_out = os.path.join(OUT, "cli.exr")
    p = subprocess.run([cli(), "denoise", h0, "--half", h1, "-f", "box", "-o", cli_out], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    got, want = rgb(os.path.join(OUT, "halves.exr")), rgb(cli_out)
    assert np.array_equal(got, want), f"the add-on's result differs from the CLI's by {np.abs(got - want).max()}"
    assert np.abs(got - mean).max() > 1e-3, "box changed nothing"
    print(f"render_halves: 64x48, 8 samples as two halves of 4; their mean vs the 8-spp render {err:.1e}; "
          f"the result is the CLI's --half bit for bit; settings put back")


def check_install_zip():
    r, log = run_blender()
    assert r["has_settings"] and r["panel"]
    assert r["menus"] == {"TOPBAR_MT_render": ["draw_render_menu"], "NODE_MT_add": ["draw_compositor_add_menu"]}, r["menus"]
    assert r["filters"] == mcrecon.filter_names()
    scripts = os.path.join(OUT, "scripts")
    assert os.path.realpath(r["native_file"]).startswith(os.path.realpath(scripts)), r["native_file"]
    print(f"installed from the zip into {scripts}; native module {os.path.basename(r['native_file'])}")


{"render_box": lambda: check_render("box"), "render_auto": lambda: check_render("auto"),
 "render_bilateral": lambda: check_render("bilateral", box_radius=bilateral_radius()),
 "passes": check_passes, "anim_bmfr": check_anim, "anim_accumulate": check_anim_accumulate,
 "errors": check_errors, "light_passes": check_light_passes,
 "composite": check_composite, "install_zip": check_install_zip, "hygiene": check_hygiene,
 "png_anim": check_png_anim, "denoise_files": check_denoise_files,
 "composite_before": check_composite_before, "export_deep": check_export_deep,
 "render_halves": check_render_halves}[CASE]()
print("OK")
