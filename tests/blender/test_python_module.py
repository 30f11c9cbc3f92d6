"""The `mcrecon` Python module (run with Debian's /usr/bin/python3 by ctest as blender_python_module).

- filters() matches `mcrecon filters --json` exactly;
- box and bilateral on numpy arrays read from samples/data/room/room_16spp.exr (OpenImageIO)
  match `mcrecon denoise` bit for bit; denoise_file and Session do too;
- errors raise mcrecon.Error naming the parameter / filter / pass, with .kind.
Environment: MCRECON_BIN, MCRECON_SOURCE_DIR, MCRECON_PYTHON_DIR (the module's folder).
"""
import json
import os
import subprocess
import sys
import tempfile
import threading

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.environ["MCRECON_PYTHON_DIR"])
import mcrecon  # noqa: E402

SRC = os.environ["MCRECON_SOURCE_DIR"]
BIN = os.environ["MCRECON_BIN"]
ROOM = os.path.join(SRC, "samples", "data", "room", "room_16spp.exr")


def cli(*args):
    p = subprocess.run([BIN, *args], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, f"mcrecon {' '.join(args)} exited {p.returncode}: {p.stderr}"
    return p.stdout


def read_channels(path):
    inp = oiio.ImageInput.open(path)
    assert inp, oiio.geterror()
    names = list(inp.spec().channelnames)
    px = inp.read_image(0, 0, 0, len(names), "float")
    inp.close()
    return names, np.ascontiguousarray(px, dtype=np.float32)


def group(names, px, prefix, suffixes):
    return np.ascontiguousarray(np.stack([px[:, :, names.index(prefix + "." + s)] for s in suffixes], axis=-1))


def expect_error(fn, kind, *words):
    try:
        fn()
    except mcrecon.Error as e:
        msg = str(e)
        assert e.kind == kind, f"kind {e.kind!r}, expected {kind!r} ({msg})"
        for w in words:
            assert w in msg, f"error message {msg!r} does not name {w!r}"
        assert isinstance(e, RuntimeError)
        return msg
    raise AssertionError(f"no mcrecon.Error ({kind}) raised")


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
        ref = opx[:, :, [onames.index(c) for c in "RGB"]]
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
    print("errors: mcrecon.Error with kind and message naming filter / parameter / pass / file")


if __name__ == "__main__":
    assert (mcrecon.Error.__module__, mcrecon.Error.__name__) == ("mcrecon", "Error"), mcrecon.Error
    assert issubclass(mcrecon.Error, RuntimeError)
    with tempfile.TemporaryDirectory(prefix="mcrecon_py_") as tmp:
        test_filters_match_cli()
        test_arrays_match_cli(tmp)
        test_two_threads_filter_at_once()
        test_gil_released_while_filtering()
        test_errors(tmp)
    print("OK")
