"""The `mcrecon` Python module (run with Debian's /usr/bin/python3 by ctest as blender_python_module).

- filters() matches `mcrecon filters --json` exactly;
- box and bilateral on numpy arrays read from samples/data/room/room_16spp.exr (OpenImageIO)
  match `mcrecon denoise` bit for bit; denoise_file and Session do too;
- accumulate=True (Session on files and arrays, denoise_file, denoise_sequence) over frames 1-4 of
  the anim sample matches `mcrecon denoise --accumulate` bit for bit (and differs from the plain run);
- needs() agrees with `mcrecon info --json` (which filters can run, which passes they use) and
  changes with the settings; Session.notes() holds the unused setting `--verbose` prints;
- filter "auto" is listed; denoise_file returns its notes (what it chose, as `--verbose` prints) and
  its output is the chosen filter's bit for bit;
- denoise_file(display={...}) writes PNG/TIFF/JPEG as `mcrecon denoise --view ...` does;
- errors raise mcrecon.Error naming the parameter / filter / pass, with .kind.
Environment: MCRECON_BIN, MCRECON_SOURCE_DIR, MCRECON_PYTHON_DIR (the module's folder).
"""
import json
import os
import re
import subprocess
import sys
import tempfile
import threading

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from module_testutil import expect_error, mcrecon  # noqa: E402

SRC = os.environ["MCRECON_SOURCE_DIR"]
BIN = os.environ["MCRECON_BIN"]
ROOM = os.path.join(SRC, "samples", "data", "room", "room_16spp.exr")
ANIM = os.path.join(SRC, "samples", "data", "anim", "anim_1spp_####.exr")
PRODUCT = os.path.join(SRC, "samples", "data", "product", "product_16spp.exr")
FENCE_HALF0 = os.path.join(SRC, "samples", "data", "fence", "fence_16spp_half0.exr")
FENCE_HALF1 = os.path.join(SRC, "samples", "data", "fence", "fence_16spp_half1.exr")


def cli(*args, stderr=False):
    p = subprocess.run([BIN, *args], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, f"mcrecon {' '.join(args)} exited {p.returncode}: {p.stderr}"
    return p.stderr if stderr else p.stdout


def read_channels(path):
    inp = oiio.ImageInput.open(path)
    assert inp, oiio.geterror()
    names = list(inp.spec().channelnames)
    px = inp.read_image(0, 0, 0, len(names), "float")
    inp.close()
    return names, np.ascontiguousarray(px, dtype=np.float32)


def group(names, px, prefix, suffixes):
    return np.ascontiguousarray(np.stack([px[:, :, names.index(prefix + "." + s)] for s in suffixes], axis=-1))


def test_filters_match_cli():
    from_cli = json.loads(cli("filters", "--json"))["filters"]
    from_py = mcrecon.filters()
    assert from_py == from_cli, "mcrecon.filters() differs from `mcrecon filters --json`"
    assert mcrecon.filter_names() == [f["name"] for f in from_cli]
    for entry in from_cli:
        assert mcrecon.filter_info(entry["name"]) == entry, f"filter_info({entry['name']!r}) differs from the CLI"
    print(f"filters(): {len(from_py)} filters match the CLI")


def test_arrays_match_cli(tmp):
    names, px = read_channels(ROOM)
    L = "ViewLayer"
    passes = dict(
        colour=group(names, px, L + ".Combined", "RGB"),
        alpha=group(names, px, L + ".Combined", "A"),
        albedo=group(names, px, L + ".Denoising Albedo", "RGB"),
        normal=group(names, px, L + ".Denoising Normal", "XYZ"),
        position=group(names, px, L + ".Position", "XYZ"),
        depth=group(names, px, L + ".Depth", "Z"),
    )
    cases = [("box", {"radius": 2}, ["radius=2"], ["colour", "alpha"]),
             ("bilateral", {}, [], list(passes))]
    for filt, params, sets, used in cases:
        assert filt in mcrecon.filter_names(), f"filter {filt!r} is not registered"
        out = os.path.join(tmp, f"cli_{filt}.exr")
        args = ["denoise", ROOM, "-o", out, "-f", filt]
        for s in sets:
            args += ["--set", s]
        cli(*args)
        onames, opx = read_channels(out)
        ref = opx[:, :, [onames.index(c) for c in "RGBA"]]  # alpha given: RGBA back (room's: 1, kept)
        got = mcrecon.denoise(filt, params=params, **{k: passes[k] for k in used})
        assert got.dtype == np.float32 and got.shape == ref.shape, (got.dtype, got.shape, ref.shape)
        assert np.array_equal(got, ref), f"{filt}: numpy result differs from the CLI (max |d| {np.abs(got - ref).max()})"
        # The file route and a Session give the same pixels.
        out2 = os.path.join(tmp, f"py_{filt}.exr")
        t = mcrecon.denoise_file(ROOM, out2, filt, params)
        assert set(t) >= {"read_ms", "filter_ms", "write_ms", "total_ms"}
        assert np.array_equal(read_channels(out2)[1], opx), f"{filt}: denoise_file differs from the CLI"
        s = mcrecon.Session(filt, params)
        assert np.array_equal(s.denoise(**{k: passes[k] for k in used}), ref)
        print(f"{filt}: arrays, denoise_file and Session match `mcrecon denoise` bit for bit")


def test_alpha_is_filtered_as_the_cli_does(tmp):
    # A transparent render (Film > Transparent, a shadow catcher): the alpha filtered by a run of
    # its own, the same bits by arrays, Session and file as by `mcrecon denoise`; alpha=keep keeps it.
    names, px = read_channels(PRODUCT)
    L = "ViewLayer"
    passes = dict(colour=group(names, px, L + ".Combined", "RGB"), alpha=group(names, px, L + ".Combined", "A"),
                  albedo=group(names, px, L + ".Denoising Albedo", "RGB"),
                  normal=group(names, px, L + ".Denoising Normal", "XYZ"), normal_space="camera",
                  geometry_normal=group(names, px, L + ".Normal", "XYZ"),
                  position=group(names, px, L + ".Position", "XYZ"), depth=group(names, px, L + ".Depth", "Z"))
    out = os.path.join(tmp, "alpha_cli.exr")
    cli("denoise", PRODUCT, "-o", out, "-f", "pwaf")
    onames, opx = read_channels(out)
    ref = opx[:, :, [onames.index(c) for c in "RGBA"]]
    assert not np.array_equal(ref[:, :, 3], passes["alpha"][:, :, 0]), "the CLI kept the alpha"
    got = mcrecon.Session("pwaf").denoise(**passes)
    assert got.shape == ref.shape and np.array_equal(got, ref), "Session.denoise's RGBA differs from the CLI's"
    kept = mcrecon.denoise("pwaf", params={"alpha": "keep"}, **passes)
    assert np.array_equal(kept[:, :, 3], passes["alpha"][:, :, 0]) and np.array_equal(kept[:, :, :3], ref[:, :, :3])
    print("alpha: filtered alike by arrays and the CLI (alpha=keep keeps it, the colour's bits the same)")


def test_halves_match_cli(tmp):
    # half= as --half: the mean of the two half buffers filtered, with the noise from their
    # difference; the same bits by Session and by the module function; the input as its own half,
    # or a missing one, is refused by name.
    want = os.path.join(tmp, "half_cli.exr")
    cli("denoise", FENCE_HALF0, "--half", FENCE_HALF1, "-o", want, "-f", "pwaf")
    expected = read_channels(want)[1]
    got = os.path.join(tmp, "half_py.exr")
    mcrecon.denoise_file(FENCE_HALF0, got, "pwaf", half=FENCE_HALF1)
    assert np.array_equal(read_channels(got)[1], expected), "denoise_file(half=) differs from --half"
    mcrecon.Session("pwaf").denoise_file(FENCE_HALF0, got, half=FENCE_HALF1)
    assert np.array_equal(read_channels(got)[1], expected), "Session.denoise_file(half=) differs from --half"
    one = os.path.join(tmp, "half_one.exr")
    mcrecon.denoise_file(FENCE_HALF0, one, "pwaf")
    assert not np.array_equal(read_channels(one)[1], expected), "half= changed nothing"
    expect_error(lambda: mcrecon.denoise_file(FENCE_HALF0, got, "pwaf", half=FENCE_HALF0), "invalid_argument",
                 "is the input", FENCE_HALF0)
    expect_error(lambda: mcrecon.denoise_file(FENCE_HALF0, got, "pwaf", half=os.path.join(tmp, "none.exr")),
                 "file_not_found", "none.exr")
    print("half=: denoise_file and Session match `mcrecon denoise --half` bit for bit")


def test_auto_reports_its_choice(tmp):
    """filter='auto' in every entry point: listed, its table as the CLI's, and denoise_file's notes
    name the filter it ran; the output is that filter's, bit for bit (the oracle for the report)."""
    assert "auto" in mcrecon.filter_names() and mcrecon.filter_names()[-1] == "auto", mcrecon.filter_names()
    info = mcrecon.filter_info("auto")
    assert {p["name"] for p in info["parameters"]} == {"sample_fraction", "converged", "min_gain", "kept_firefly_k", "pairs",
                                                       "exposure", "components", "alpha"}, info["parameters"]
    assert info in mcrecon.filters()
    out = os.path.join(tmp, "auto_py.exr")
    t = mcrecon.denoise_file(ROOM, out, "auto")
    assert set(t) >= {"read_ms", "filter_ms", "write_ms", "total_ms", "notes"}, t
    chosen = [n[len("auto: chose "):].split()[0] for n in t["notes"] if n.startswith("auto: chose ")]
    assert len(chosen) == 1 and any(n.startswith("auto: estimated relMSE") for n in t["notes"]), t["notes"]
    assert chosen[0] in mcrecon.filter_names() and chosen[0] != "auto", t["notes"]
    assert t["chosen"] == {"beauty": chosen[0]}, t
    assert mcrecon.denoise_file(ROOM, os.path.join(tmp, "box_py.exr"), "box")["chosen"] is None
    # The same notes as `mcrecon denoise --verbose` prints, and as Session.notes() after a run.
    err = cli("denoise", ROOM, "-o", os.path.join(tmp, "auto_cli.exr"), "-f", "auto", "--verbose", stderr=True)
    prefix = "mcrecon: " + ROOM + ": "
    assert [l[len(prefix):] for l in err.splitlines() if l.startswith(prefix)] == t["notes"], (err, t["notes"])
    s = mcrecon.Session("auto")
    assert s.denoise_file(ROOM, os.path.join(tmp, "auto_session.exr"))["notes"] == s.notes() == t["notes"]
    assert s.chosen() == t["chosen"], s.chosen()
    want = os.path.join(tmp, "auto_chosen.exr")
    mcrecon.denoise_file(ROOM, want, chosen[0])
    assert np.array_equal(read_channels(out)[1], read_channels(want)[1]), f"auto's output is not {chosen[0]}'s"
    # Arrays: colour alone (the filters that need a feature pass are skipped, and said so).
    names, px = read_channels(ROOM)
    colour = group(names, px, "ViewLayer.Combined", "RGB")
    s = mcrecon.Session("auto")
    got = s.denoise(colour)
    assert got.shape == colour.shape and np.isfinite(got).all()
    assert len([n for n in s.notes() if n.startswith("auto: chose ")]) == 1, s.notes()
    assert s.chosen() == {"beauty": re.search(r"auto: chose (?:the )?(\S+)", " ".join(s.notes())).group(1)}, s.chosen()
    lacking = [f["name"] for f in mcrecon.filters() if not f["temporal"] and f["name"] != "auto"
               and set(mcrecon.needs(f["name"])["required"]) - {"colour"}]
    skipped = [n for n in s.notes() if n.startswith("auto: candidates skipped: ")]
    assert [re.findall(r"(\w+) \(no ", n) for n in skipped] == ([lacking] if lacking else []), (lacking, s.notes())
    print(f"auto: chose {chosen[0]} on the room sample; notes as `--verbose`; output is {chosen[0]}'s bit for bit")


def frame_path(pattern, f):
    return pattern.replace("####", "%04d" % f)


def same_bits(a, b):
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def test_accumulate_matches_cli(tmp):
    frames = range(1, 5)
    want, plain = os.path.join(tmp, "acc_cli_####.exr"), os.path.join(tmp, "plain_cli_####.exr")
    cli("denoise", ANIM, "-o", want, "-f", "box", "--frames", "1-4", "--accumulate")
    cli("denoise", ANIM, "-o", plain, "-f", "box", "--frames", "1-4")
    wanted = [read_channels(frame_path(want, f))[1] for f in frames]
    for f in frames[1:]:  # so a module that drops accumulate=True fails below
        assert not same_bits(wanted[f - 1], read_channels(frame_path(plain, f))[1]), \
            f"frame {f}: --accumulate gives the plain filter's pixels"

    # Session on files.
    s = mcrecon.Session("box", accumulate=True)
    assert s.accumulate and s.temporal and not mcrecon.Session("box").temporal
    for f in frames:
        out = frame_path(os.path.join(tmp, "acc_session_####.exr"), f)
        s.denoise_file(frame_path(ANIM, f), out)
        assert same_bits(read_channels(out)[1], wanted[f - 1]), f"Session(accumulate=True) frame {f} differs"
    # denoise_sequence.
    outs = mcrecon.denoise_sequence(ANIM, os.path.join(tmp, "acc_seq_####.exr"), 1, 4, "box", accumulate=True)
    for f, out in zip(frames, outs):
        assert same_bits(read_channels(out)[1], wanted[f - 1]), f"denoise_sequence(accumulate=True) frame {f} differs"
    # Session on arrays: colour, alpha and what the accumulation reads (world position and
    # normal, motion, the Diffuse/Glossy Color by which it tells mirrors).
    s = mcrecon.Session("box", accumulate=True)
    for f in frames:
        names, px = read_channels(frame_path(ANIM, f))
        L = "ViewLayer"
        got = s.denoise(group(names, px, L + ".Combined", "RGB"), alpha=group(names, px, L + ".Combined", "A"),
                        position=group(names, px, L + ".Position", "XYZ"),
                        normal=group(names, px, L + ".Normal", "XYZ"), motion=group(names, px, L + ".Vector", "XYZW"),
                        diffuse_colour=group(names, px, L + ".DiffCol", "RGB"),
                        glossy_colour=group(names, px, L + ".GlossCol", "RGB"))
        onames = read_channels(frame_path(want, f))[0]
        ref = np.ascontiguousarray(wanted[f - 1][:, :, [onames.index(c) for c in "RGBA"]])
        assert same_bits(got, ref), f"Session(accumulate=True).denoise on arrays, frame {f} differs"
    # denoise_file: one frame, as `mcrecon denoise FILE --accumulate`.
    one = os.path.join(tmp, "acc_one.exr")
    cli("denoise", frame_path(ANIM, 2), "-o", one, "-f", "box", "--accumulate")
    mine = os.path.join(tmp, "acc_one_py.exr")
    mcrecon.denoise_file(frame_path(ANIM, 2), mine, "box", accumulate=True)
    assert same_bits(read_channels(mine)[1], read_channels(one)[1]), "denoise_file(accumulate=True) differs"
    print("accumulate=True: Session (files, arrays), denoise_sequence, denoise_file match `mcrecon denoise "
          "--accumulate` bit for bit")


def test_sequence_warmup_matches_cli(tmp):
    # warmup=N as --warmup N: frames 3-4 with 2 frames of history = frames 3-4 of a run over 1-4.
    want = os.path.join(tmp, "wu_cli_####.exr")
    cli("denoise", ANIM, "-o", want, "-f", "box", "--accumulate", "--frames", "3-4", "--warmup", "2")
    cold = os.path.join(tmp, "wu_cold_####.exr")
    mcrecon.denoise_sequence(ANIM, cold, 3, 4, "box", accumulate=True)
    outs = mcrecon.denoise_sequence(ANIM, os.path.join(tmp, "wu_py_####.exr"), 3, 4, "box", accumulate=True, warmup=2)
    for f, out in zip((3, 4), outs):
        assert same_bits(read_channels(out)[1], read_channels(frame_path(want, f))[1]), f"warmup=2 frame {f} differs"
    assert not same_bits(read_channels(frame_path(cold, 3))[1], read_channels(frame_path(want, 3))[1]), \
        "warmup=2 gives the cold start's pixels"
    try:
        mcrecon.denoise_sequence(ANIM, os.path.join(tmp, "wu_bad_####.exr"), 1, 2, "box", accumulate=True, warmup=1)
        raise AssertionError("a warmup frame before the sequence was accepted")
    except mcrecon.Error as e:
        assert "anim_1spp_0000.exr" in str(e) and "warmup" in str(e), str(e)
    print("denoise_sequence(warmup=2) matches `mcrecon denoise --warmup 2` bit for bit")


def test_needs_match_info_and_settings(tmp):
    # `mcrecon info` says which filters can run with their defaults: needs() of the defaults. A
    # colour-only file lacks what some filters require; its sample count is a pass the defaults
    # use (the hole fill) that no filter's static list names.
    only_colour = os.path.join(tmp, "colour_only.exr")
    spec = oiio.ImageSpec(16, 12, 5, "float")
    spec.channelnames = ("R", "G", "B", "A", "sample_count.Y")
    out = oiio.ImageOutput.create(only_colour)
    assert out.open(only_colour, spec) and out.write_image(np.full((12, 16, 5), 1.0, np.float32)), out.geterror()
    out.close()
    for path in (ROOM, only_colour):
        info = json.loads(cli("info", "--json", path))
        present = set(info["roles"])
        assert [f["name"] for f in info["filters"]] == mcrecon.filter_names()
        deep = {f["name"] for f in mcrecon.filters() if f["input"] == "deep"}
        lightfield = {f["name"] for f in mcrecon.filters() if f["lightfield"]}
        for entry in info["filters"]:
            n = mcrecon.needs(entry["name"])
            flat = ["light-field (deep EXR) input"] if entry["name"] in lightfield else \
                ["per-sample (deep) input"] if entry["name"] in deep and not info["deep"] else []
            assert entry["missing"] == [r for r in n["required"] if r not in present] + flat, (path, entry, n)
            assert entry["uses"] == [r for r in n["optional"] if r in present], (path, entry, n)
            assert entry["can_run"] == (not entry["missing"])
    colour_info = json.loads(cli("info", "--json", only_colour))
    assert "sample_count" in colour_info["roles"], colour_info["roles"]
    assert any(not f["can_run"] for f in colour_info["filters"])
    assert all("sample_count" in f["uses"] for f in colour_info["filters"] if f["can_run"])
    # Settings change what is needed.
    box = mcrecon.needs("box")
    assert box["required"] == ["colour"] and box["why"] == {} and "albedo" not in box["optional"], box
    demod = mcrecon.needs("box", {"demodulate": True})
    assert "albedo" in demod["required"] and demod["why"]["albedo"] == "demodulate=true", demod
    acc = mcrecon.needs("box", accumulate=True)
    assert {"position", "normal"} <= set(acc["required"]) and "motion" in acc["optional"], acc
    assert acc["why"]["position"] == "accumulate", acc
    assert mcrecon.Session("box", {"demodulate": True}).needs() == demod
    assert mcrecon.Session("box", accumulate=True).needs() == acc
    expect_error(lambda: mcrecon.needs("box", {"radius": -1}), "parameter_out_of_range", "radius")
    print("needs(): matches `mcrecon info` on two files and follows the settings")


def test_notes_hold_unused_settings(tmp):
    # firefly_k is on by default: off, firefly_radius is the unused setting.
    err = cli("denoise", ROOM, "-o", os.path.join(tmp, "n.exr"), "-f", "box", "--set", "firefly_k=0",
              "--set", "firefly_radius=5", "--verbose", stderr=True)
    notes = [l[len("mcrecon: note: "):] for l in err.splitlines() if l.startswith("mcrecon: note: ")]
    assert notes == ["firefly_radius has no effect with firefly_k=0"], err
    s = mcrecon.Session("box", {"firefly_k": 0.0, "firefly_radius": 5})
    assert s.notes() == notes, s.notes()
    s.denoise_file(ROOM, os.path.join(tmp, "n_py.exr"))
    assert s.notes()[:1] == notes, s.notes()  # still first after a run
    assert mcrecon.Session("box").notes() == []
    print("Session.notes(): the unused setting `mcrecon denoise --verbose` prints")


def test_two_threads_filter_at_once():
    c = np.random.default_rng(1).random((64, 96, 3), dtype=np.float32)
    results = [None, None]

    def work(i):
        results[i] = mcrecon.denoise("box", c, params={"radius": 3})
    th = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in th:
        t.start()
    for t in th:
        t.join()
    assert results[0] is not None and results[1] is not None, "a filtering thread raised"
    assert np.array_equal(results[0], results[1]), "two threads filtering the same array disagree"
    # numpy scalars are accepted as parameter values.
    a = mcrecon.denoise("box", c, params={"radius": np.int64(2), "demodulate": np.bool_(False)})
    assert np.array_equal(a, mcrecon.denoise("box", c, params={"radius": 2, "demodulate": False}))


def test_gil_released_while_filtering():
    """Another Python thread runs while mcrecon.denoise filters, shown without any timing threshold.

    The switch interval is made so long that the main thread never hands the GIL over by itself
    while it runs Python code. The helper is woken just before the call and then needs the GIL to
    record that it ran, so it can run only where the main thread gives the GIL up of its own
    accord: between go.set() and reading the record, the only such place is inside
    mcrecon.denoise. With the GIL held there the record is always empty; with it released the
    helper, runnable before the call starts, runs during a single-threaded bilateral filter of a
    megapixel that takes far longer than any scheduling delay."""
    colour = np.random.default_rng(2).random((768, 1024, 3), dtype=np.float32)
    params = {"spatial_sigma": 5.0}
    ran = []
    go = threading.Event()

    def helper():
        go.wait()
        ran.append(True)

    helper_thread = threading.Thread(target=helper)
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e6)
    try:
        helper_thread.start()
        go.set()
        out = mcrecon.denoise("bilateral", colour, params=params, threads=1)
        helper_ran = len(ran)
    finally:
        sys.setswitchinterval(interval)
    helper_thread.join()
    assert helper_ran == 1, "no other Python thread ran while mcrecon.denoise filtered: is the GIL held?"
    assert out.shape == colour.shape
    print("GIL released while filtering: another Python thread ran during mcrecon.denoise")


def test_bands_match_the_whole_frame(tmp):
    """denoise_file(max_memory_mb=N) filters in bands of rows, as `--max-memory N`: the whole
    frame's pixels bit for bit, the bands named in the notes; a temporal run is refused."""
    whole, banded = os.path.join(tmp, "whole.exr"), os.path.join(tmp, "banded.exr")
    mcrecon.denoise_file(ROOM, whole, "pwaf")
    t = mcrecon.denoise_file(ROOM, banded, "pwaf", max_memory_mb=300)
    assert any(re.match(r"\d+ bands? of \d+ rows", n) for n in t["notes"]), t["notes"]
    assert np.array_equal(read_channels(whole)[1], read_channels(banded)[1]), "bands differ from the whole frame"
    expect_error(lambda: mcrecon.denoise_file(ROOM, os.path.join(tmp, "b.exr"), "bmfr", max_memory_mb=300),
                 "invalid_argument", "temporal")
    print("max_memory_mb: bands give the whole frame's pixels")


def test_display_outputs_match_cli(tmp):
    """denoise_file(display=...) writes what `mcrecon denoise --view ...` writes, bit for bit."""
    for name, args, display in (("s.png", [], None), ("f.tif", ["--view", "Filmic", "--exposure", "0.5"],
                                                        {"view": "Filmic", "exposure": 0.5}),
                                ("g.jpg", ["--gamma", "1.2"], {"gamma": 1.2})):
        mine, theirs = os.path.join(tmp, "py_" + name), os.path.join(tmp, "cli_" + name)
        mcrecon.denoise_file(ROOM, mine, "box", display=display)
        cli("denoise", ROOM, "-o", theirs, "-f", "box", *args)
        a, b = oiio.ImageBuf(mine), oiio.ImageBuf(theirs)
        assert a.spec().format == b.spec().format and a.nchannels == b.nchannels, name
        assert np.array_equal(a.get_pixels(oiio.FLOAT), b.get_pixels(oiio.FLOAT)), f"{name}: module and CLI differ"
    out = os.path.join(tmp, "o.png")
    expect_error(lambda: mcrecon.denoise_file(ROOM, out, "box", display={"view": "Filmc"}), "invalid_argument",
                 "view 'Filmc'", "Filmic")
    expect_error(lambda: mcrecon.denoise_file(ROOM, out, "box", display={"veiw": "Filmic"}), "invalid_argument",
                 "'veiw'")
    expect_error(lambda: mcrecon.denoise_file(ROOM, out, "box", display={"exposure": "high"}), "invalid_argument",
                 "exposure", "'high'")
    expect_error(lambda: mcrecon.denoise_file(ROOM, out, "box", display={"bit_depth": 12}), "invalid_argument",
                 "bit_depth", "12")
    expect_error(lambda: mcrecon.denoise_file(ROOM, out, "box", display="Filmic"), "invalid_argument", "'Filmic'")
    expect_error(lambda: mcrecon.denoise_file(ROOM, out, "box", keep_passes=True), "invalid_argument", "keep_passes")
    assert not os.path.exists(out)
    print("display outputs: PNG/TIFF/JPEG as the CLI writes them; bad display settings raise mcrecon.Error")


def test_errors(tmp):
    c = np.zeros((8, 8, 3), np.float32)
    expect_error(lambda: mcrecon.denoise("no_such_filter", c), "unknown_filter", "no_such_filter")
    expect_error(lambda: mcrecon.denoise("box", c, params={"no_such_param": 1}), "unknown_parameter", "no_such_param")
    expect_error(lambda: mcrecon.denoise("box", c, params={"radius": -5}), "parameter_out_of_range", "radius")
    expect_error(lambda: mcrecon.denoise("box", c, params={"radius": "wide"}), "bad_parameter_value", "radius")
    expect_error(lambda: mcrecon.denoise("box", c, albedo=np.zeros((4, 4, 3), np.float32)), "size_mismatch", "albedo")
    expect_error(lambda: mcrecon.denoise_file(os.path.join(tmp, "missing.exr"), os.path.join(tmp, "o.exr"), "box"),
                 "file_not_found", "missing.exr")
    # bmfr needs feature passes besides the colour: a colour-only call names the first one.
    missing = [r for r in mcrecon.filter_info("bmfr")["required_passes"] if r != "colour"]
    assert missing, "bmfr requires no feature pass"
    expect_error(lambda: mcrecon.Session("bmfr").denoise(c), "missing_pass", missing[0])
    expect_error(lambda: mcrecon.filter_info("nope"), "unknown_filter", "nope")
    for bad in ("maybe", 2):
        expect_error(lambda: mcrecon.Session("box", accumulate=bad), "invalid_argument", "accumulate", repr(bad))
        expect_error(lambda: mcrecon.denoise_file(ROOM, os.path.join(tmp, "o.exr"), "box", accumulate=bad),
                     "invalid_argument", "accumulate", repr(bad))
    # Accumulation's passes are checked before any work, naming the setting.
    expect_error(lambda: mcrecon.Session("box", accumulate=True).denoise(c), "missing_pass", "position", "accumulate")
    print("errors: mcrecon.Error with kind and message naming filter / parameter / pass / file")


if __name__ == "__main__":
    assert (mcrecon.Error.__module__, mcrecon.Error.__name__) == ("mcrecon", "Error"), mcrecon.Error
    assert issubclass(mcrecon.Error, RuntimeError)
    with tempfile.TemporaryDirectory(prefix="mcrecon_py_") as tmp:
        test_filters_match_cli()
        test_arrays_match_cli(tmp)
        test_alpha_is_filtered_as_the_cli_does(tmp)
        test_halves_match_cli(tmp)
        test_auto_reports_its_choice(tmp)
        test_accumulate_matches_cli(tmp)
        test_sequence_warmup_matches_cli(tmp)
        test_needs_match_info_and_settings(tmp)
        test_notes_hold_unused_settings(tmp)
        test_two_threads_filter_at_once()
        test_gil_released_while_filtering()
        test_display_outputs_match_cli(tmp)
        test_bands_match_the_whole_frame(tmp)
        test_errors(tmp)
    print("OK")
