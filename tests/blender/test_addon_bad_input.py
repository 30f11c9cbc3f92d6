"""The bad-input matrix for the Blender add-on (ctest blender_addon_bad_input): every case in ONE
headless Blender process, checked from outside.

    /usr/bin/python3 test_addon_bad_input.py          (the driver; runs Blender on this file)
    blender -b --factory-startup --python-exit-code 1 --python test_addon_bad_input.py -- PLAN.json

The driver builds each case's inputs in its own directory (tests/python/bad_input_files.py),
hashes everything there, runs Blender once, then checks per case: the operator was cancelled with
an error report (or the render handler logged `mcrecon: ERROR`) naming the file / parameter as
given, every input is byte-identical, and no output or temp file is left. The render cases check
that the render Blender wrote survives (output_path equal to the render's own file), and that an
animation whose output path has no #### is refused or writes one file per frame.

Environment: MCRECON_BLENDER, MCRECON_ADDON_STAGE, MCRECON_SOURCE_DIR, MCRECON_TEST_TMP.
Exit 77 = skipped (ctest SKIP_RETURN_CODE).
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

# Cases: (name, what runs, arguments, what the message must name). Operator cases call
# bpy.ops.mcrecon.denoise_files with the given properties (paths relative to the case dir).
OPERATOR_CASES = [
    ("op_output_same_path", dict(filepath="in.exr", output="in.exr"), ["in.exr"]),
    ("op_output_dot_spelling", dict(filepath="in.exr", output="./in.exr"), ["in.exr"]),
    ("op_output_symlink_to_input", dict(filepath="in.exr", output="link.exr"), ["link.exr"]),
    ("op_output_hardlink_to_input", dict(filepath="in.exr", output="hard.exr"), ["hard.exr"]),
    ("op_output_chardev_null", dict(filepath="in.exr", output="null.exr"), ["null.exr"]),
    ("op_output_fifo", dict(filepath="in.exr", output="fifo_out.exr"), ["fifo_out.exr"]),
    ("op_output_directory", dict(filepath="in.exr", output="outdir.exr"), ["outdir.exr"]),
    ("op_output_in_missing_directory", dict(filepath="in.exr", output="nodir/out.exr"), ["nodir"]),
    ("op_missing_input", dict(filepath="nosuch.exr", output="out.exr"), ["nosuch.exr"]),
    ("op_truncated_input", dict(filepath="cut.exr", output="out.exr"), ["cut.exr"]),
    ("op_sequence_output_without_hash", dict(filepath="in_####.exr", output="out.exr", frame_start=1, frame_end=2),
     ["out.exr"]),
    ("op_sequence_over_its_input", dict(filepath="in_####.exr", output="in_####.exr", frame_start=1, frame_end=2),
     ["in_0001.exr"]),
    ("op_unknown_parameter", dict(filepath="in.exr", output="out.exr", extra_params="nosuch_param=1"), ["nosuch_param"]),
    ("op_out_of_range_parameter", dict(filepath="in.exr", output="out.exr", extra_params="radius=1e20"),
     ["radius", "1e20"]),
]
RENDER_CASES = ["render_output_path_is_the_render", "render_animation_output_without_hash"]


# ============================================================================ inside Blender

def blender_main(plan_path):
    import addon_utils
    import bpy
    with open(plan_path) as f:
        plan = json.load(f)
    sys.path.insert(0, os.environ["MCRECON_ADDON_STAGE"])
    assert addon_utils.enable("mcrecon_addon", default_set=True, handle_error=None), "add-on did not enable"
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 16, 12, 100
    scene.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    scene.render.use_compositing = False
    mc = scene.mcrecon
    mc.filter = "box"
    results = {}
    for name, d, props in plan["operator"]:
        props = dict(props)
        mc.extra_params = props.pop("extra_params", "")
        for k in ("filepath", "output"):
            props[k] = os.path.join(d, props[k])  # join keeps "./": d/./in.exr
        r = {"result": None, "error": ""}
        print("=== case", name, flush=True)
        try:
            r["result"] = sorted(bpy.ops.mcrecon.denoise_files(filter="box", **props))
        except RuntimeError as e:  # bpy.ops raises on an ERROR report
            r["error"] = str(e)
        except Exception as e:  # recorded, not fatal: the next cases still run
            r["error"] = "UNEXPECTED %s: %s" % (type(e).__name__, e)
        results[name] = r
    mc.extra_params = ""
    mc.enabled = True
    for name, d in plan["render"]:
        print("=== case", name, flush=True)
        mc.last_message = ""
        if name == "render_output_path_is_the_render":
            scene.frame_start = scene.frame_end = scene.frame_current = 1
            scene.render.filepath = os.path.join(d, "render")
            mc.output_path = os.path.join(d, "render.exr")
            bpy.ops.render.render(write_still=True)
        else:
            scene.frame_start, scene.frame_end = 1, 2
            scene.render.filepath = os.path.join(d, "anim_####")
            mc.output_path = os.path.join(d, "den.exr")
            bpy.ops.render.render(animation=True)
        results[name] = {"message": mc.last_message}
    with open(plan["result"], "w") as f:
        json.dump(results, f, indent=1)


# ============================================================================ the driver

def driver_main():
    import shutil
    import subprocess
    sys.path.insert(0, os.path.join(os.path.dirname(HERE), "python"))
    import bad_input_files as bf
    import OpenImageIO as oiio

    blender = os.environ.get("MCRECON_BLENDER") or shutil.which("blender")
    stage = os.environ.get("MCRECON_ADDON_STAGE")
    if not blender or not stage or not os.path.isdir(os.path.join(stage, "mcrecon_addon")):
        print("SKIPPED: no blender or no staged add-on (MCRECON_BLENDER, MCRECON_ADDON_STAGE)")
        sys.exit(77)
    root = os.path.join(os.environ.get("MCRECON_TEST_TMP") or "/tmp", "addon_bad_input")
    shutil.rmtree(root, ignore_errors=True)
    os.makedirs(root)

    def case_dir(name):
        d = os.path.join(root, name)
        os.mkdir(d)
        bf.write_render(os.path.join(d, "in.exr"))
        return d

    plan = {"operator": [], "render": [], "result": os.path.join(root, "result.json")}
    before = {}
    for name, props, _ in OPERATOR_CASES:
        d = case_dir(name)
        p = lambda n: os.path.join(d, n)  # noqa: E731
        if name.endswith("symlink_to_input"):
            os.symlink("in.exr", p("link.exr"))
        elif name.endswith("hardlink_to_input"):
            os.link(p("in.exr"), p("hard.exr"))
        elif name.endswith("chardev_null"):
            bf.mknod_char(p("null.exr"), 1, 3)
        elif name.endswith("fifo"):
            os.mkfifo(p("fifo_out.exr"))
        elif name.endswith("directory") and "missing" not in name:
            os.mkdir(p("outdir.exr"))
        elif name.endswith("truncated_input"):
            bf.cut(p("in.exr"), p("cut.exr"), os.path.getsize(p("in.exr")) // 2)
        elif "sequence" in name:
            for f in (1, 2):
                bf.write_render(p("in_%04d.exr" % f), seed=f)
        before[name] = bf.snapshot(d)
        plan["operator"].append((name, d, props))
    for name in RENDER_CASES:
        d = os.path.join(root, name)
        os.mkdir(d)
        plan["render"].append((name, d))
    plan_path = os.path.join(root, "plan.json")
    with open(plan_path, "w") as f:
        json.dump(plan, f, indent=1)

    env = dict(os.environ, BLENDER_USER_CONFIG=os.path.join(root, "config"),
               BLENDER_USER_SCRIPTS=os.path.join(root, "scripts"))
    cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python", os.path.abspath(__file__),
           "--", plan_path]
    n_cases = len(OPERATOR_CASES) + len(RENDER_CASES)
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=10 * n_cases + 30, env=env,
                           stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        started = [l for l in out.splitlines() if l.startswith("=== case")]
        print(out[-4000:])
        print("FAIL: Blender did not finish within %d s; last case started: %s"
              % (10 * n_cases + 30, started[-1] if started else "none"))
        sys.exit(1)
    log = p.stdout + p.stderr
    with open(os.path.join(root, "blender.log"), "w") as f:
        f.write(log)
    if p.returncode != 0 or not os.path.exists(plan["result"]):
        print(log[-6000:])
        print("FAIL: Blender exited %d" % p.returncode)
        sys.exit(1)
    with open(plan["result"]) as f:
        results = json.load(f)
    failures = []

    def fail(name, what):
        failures.append("%s: %s" % (name, what))

    for name, props, mentions in OPERATOR_CASES:
        d = os.path.join(root, name)
        r = results[name]
        if r["result"] is not None or not r["error"] or r["error"].startswith("UNEXPECTED"):
            fail(name, "the operator returned %s (error %r), want a cancel with an error report"
                 % (r["result"], r["error"]))
        else:
            missing = [m for m in mentions if m not in r["error"]]
            if missing:
                fail(name, "the report does not name %s: %s" % (missing, r["error"].strip()))
        diff = bf.snapshot_diff(before[name], bf.snapshot(d))
        if diff:
            fail(name, "the case directory changed (inputs must stay byte-identical, no output, no temp):\n" + diff)

    # output_path = the render's own file: the render stays the multilayer render.
    name = RENDER_CASES[0]
    d = os.path.join(root, name)
    msg = results[name]["message"]
    render = os.path.join(d, "render.exr")
    if not os.path.exists(render):
        fail(name, "the render was not written")
    else:
        inp = oiio.ImageInput.open(render)
        names = list(inp.spec().channelnames) if inp else []
        if inp:
            inp.close()
        if "ViewLayer.Combined.R" not in names:
            fail(name, "render.exr was replaced: its channels are now %s" % names)
    if "ERROR" not in msg or "render.exr" not in msg:
        fail(name, "no error naming render.exr: last message %r" % msg)
    if bf.temp_files(d) or sorted(os.listdir(d)) != ["render.exr"]:
        fail(name, "files left: %s" % sorted(os.listdir(d)))

    # An animation with one output path for every frame: either refused (an error naming it) or
    # every frame in its own complete file; never two frames into one file.
    name = RENDER_CASES[1]
    d = os.path.join(root, name)
    msg = results[name]["message"]
    refused = [l for l in log.splitlines() if l.startswith("mcrecon: ERROR") and "den.exr" in l]
    outputs = sorted(n for n in os.listdir(d) if n.startswith("den"))
    complete = []
    for n in outputs:
        inp = oiio.ImageInput.open(os.path.join(d, n))
        if inp:
            complete.append(inp.read_image(0, 0, 0, inp.spec().nchannels, "float") is not None)
            inp.close()
    if not refused and not (len(outputs) == 2 and len(complete) == 2 and all(complete)):
        fail(name, "neither an error naming den.exr nor one complete file per frame: outputs %s "
                   "(last message %r)" % (outputs, msg))
    for f in (1, 2):
        if not os.path.exists(os.path.join(d, "anim_%04d.exr" % f)):
            fail(name, "render frame %d was not written" % f)
    if bf.temp_files(d):
        fail(name, "temp files left: %s" % bf.temp_files(d))

    for name in [c[0] for c in OPERATOR_CASES] + RENDER_CASES:
        status = "FAIL" if any(f.startswith(name + ":") for f in failures) else "ok"
        print("%-40s %s" % (name, status))
    if failures:
        print("\n".join(["", "FAILURES:"] + failures))
        print("(Blender log: %s)" % os.path.join(root, "blender.log"))
        sys.exit(1)
    shutil.rmtree(root, ignore_errors=True)
    print("OK: %d add-on cases" % n_cases)


def _in_blender():
    try:
        import bpy  # noqa: F401
        return True
    except ImportError:
        return False


if __name__ == "__main__":
    if _in_blender():
        blender_main(sys.argv[sys.argv.index("--") + 1])
    else:
        driver_main()
