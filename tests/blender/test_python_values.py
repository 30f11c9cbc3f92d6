"""The `mcrecon` Python module under shared use and odd values (ctest: blender_python_values).

- one Session('bmfr', accumulate=True) used by 4 threads at once gives exactly the results of the
  same number of serial calls (the calls are serialised; every frame is the same static frame, so
  the k-th call in any order returns the k-th serial result): no crash, every output finite;
- denoise_sequence over the frame 2147483647 (first = last = INT_MAX) writes that one frame;
- an empty, negative or malformed roi, a complex, object or string array, an int parameter beyond
  2^63, a first/last beyond int: mcrecon.Error with .kind, repeating what was given; float64,
  float16 and int arrays are still cast to float32;
- a constant FLT_MAX image stays FLT_MAX with demodulate=True over a dark albedo.
Environment: MCRECON_SOURCE_DIR, MCRECON_PYTHON_DIR (the module's folder).
"""
import os
import shutil
import sys
import tempfile
import threading

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from module_testutil import expect_error, mcrecon  # noqa: E402

SRC = os.environ["MCRECON_SOURCE_DIR"]
ANIM1 = os.path.join(SRC, "samples", "data", "anim", "anim_1spp_0001.exr")
INT_MAX = 2**31 - 1


def static_frame(h=40, w=48):
    rng = np.random.default_rng(5)
    colour = rng.random((h, w, 3), dtype=np.float32)
    albedo = rng.uniform(0.2, 1.0, (h, w, 3)).astype(np.float32)
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    position = np.stack([xs * 0.1, ys * 0.1, 5.0 + 0.01 * (xs % 3)], axis=-1).astype(np.float32)
    normal = np.zeros((h, w, 3), np.float32)
    normal[..., 2] = 1.0
    return dict(colour=colour, albedo=albedo, position=position, normal=normal)


def test_shared_session_from_threads():
    frame = static_frame()
    threads, per_thread = 4, 12
    n = threads * per_thread
    serial_session = mcrecon.Session("bmfr", threads=1, accumulate=True)
    serial = [serial_session.denoise(**frame) for _ in range(n)]
    assert not np.array_equal(serial[0], serial[-1]), "the history does not change the result"

    shared = mcrecon.Session("bmfr", threads=1, accumulate=True)
    results = [[] for _ in range(threads)]
    errors = []

    def work(i):
        try:
            for _ in range(per_thread):
                results[i].append(shared.denoise(**frame))
                shared.notes()  # while the others filter
        except Exception as e:  # noqa: BLE001 (reported below)
            errors.append(repr(e))
    pool = [threading.Thread(target=work, args=(i,)) for i in range(threads)]
    for t in pool:
        t.start()
    for t in pool:
        t.join()
    assert not errors, errors
    got = [r for rs in results for r in rs]
    assert len(got) == n
    for r in got:
        assert np.isfinite(r).all()
    assert sorted(r.tobytes() for r in got) == sorted(r.tobytes() for r in serial), \
        "a Session shared by threads did not give the results of serial calls"
    # reset() from another thread: the next call starts a new history.
    t = threading.Thread(target=shared.reset)
    t.start()
    t.join()
    assert np.array_equal(shared.denoise(**frame), serial[0])
    print(f"Session('bmfr', accumulate=True) from {threads} threads: the {n} serial results")


def test_sequence_at_int_max(tmp):
    src = os.path.join(tmp, "in_####.exr")
    out = os.path.join(tmp, "out_####.exr")
    expect_error(lambda: mcrecon.denoise_sequence(src, out, INT_MAX, INT_MAX, "box"),
                 "file_not_found", "in_2147483647.exr")
    shutil.copy(ANIM1, os.path.join(tmp, f"in_{INT_MAX}.exr"))
    written = mcrecon.denoise_sequence(src, out, INT_MAX, INT_MAX, "box")
    assert written == [os.path.join(tmp, f"out_{INT_MAX}.exr")], written
    assert os.path.isfile(written[0])
    for bad in (2**31, -2**31 - 1, 2**70, 1.5, "7"):
        expect_error(lambda: mcrecon.denoise_sequence(src, out, bad, INT_MAX, "box"),
                     "invalid_argument", "first", repr(bad))
        expect_error(lambda: mcrecon.denoise_sequence(src, out, INT_MAX, bad, "box"),
                     "invalid_argument", "last", repr(bad))
    print("denoise_sequence: frame 2147483647 written once, no overflow")


def test_bad_values(tmp):
    c = np.random.default_rng(3).random((8, 8, 3), dtype=np.float32)
    form = "expects (x0, y0, x1, y1) with 0 <= x0 < x1 and 0 <= y0 < y1"
    for roi, what in [((5, 5, 5, 9), "is empty"), ((2, 6, 7, 6), "is empty"), ((7, 0, 3, 4), "is empty"),
                      ((-3, 0, 4, 4), "outside"), ((0, 0, 2**40, 4), "outside"), ((0, 0, 4), "is not 4 ints"),
                      ((0.5, 0, 4, 4), "is not 4 ints"), ("abcd", "is not 4 ints"), ((0, 0, True, 4), "is not 4 ints")]:
        expect_error(lambda: mcrecon.denoise("box", c, roi=roi), "invalid_argument", "roi " + repr(roi), what, form)
        expect_error(lambda: mcrecon.Session("box").denoise(c, roi=roi), "invalid_argument", "roi " + repr(roi), what)
    # A valid roi (numpy ints too) filters inside and keeps the input outside.
    out = mcrecon.denoise("box", c, roi=np.array([2, 2, 6, 6]))
    assert np.array_equal(out[0], c[0]) and not np.array_equal(out[2:6, 2:6], c[2:6, 2:6])

    for arr, dtype in [(c.astype(np.complex64), "complex64"), (c.astype(object), "object"),
                       (np.full((8, 8, 3), "x"), "str"), ([[["a", "b", "c"]]], "str")]:
        expect_error(lambda: mcrecon.denoise("box", arr), "invalid_argument",
                     "colour: expected a real float array, got " + dtype)
    expect_error(lambda: mcrecon.denoise("box", c, albedo=c.astype(np.complex128)), "invalid_argument",
                 "albedo: expected a real float array, got complex128")
    # Real arrays of other types are cast to float32, as before.
    for arr in (c.astype(np.float64), c.astype(np.float16), (c * 100).astype(np.int32)):
        assert np.array_equal(mcrecon.denoise("box", arr), mcrecon.denoise("box", arr.astype(np.float32)))

    # Int parameters of any size: the table's error, never a bare RuntimeError.
    for big in (2**63, 2**64, -2**64, np.uint64(2**64 - 1)):
        p = {"radius": big}
        for call in (lambda: mcrecon.denoise("box", c, params=p), lambda: mcrecon.Session("box", p),
                     lambda: mcrecon.needs("box", p),
                     lambda: mcrecon.denoise_file(ANIM1, os.path.join(tmp, "o.exr"), "box", params=p)):
            try:
                call()
                raise AssertionError(f"radius={big} accepted")
            except mcrecon.Error as e:
                assert e.kind in ("parameter_out_of_range", "bad_parameter_value"), (e.kind, str(e))
                assert "radius" in str(e), str(e)
    assert not os.path.exists(os.path.join(tmp, "o.exr"))
    print("bad values: roi, complex/object/str arrays, huge ints, first/last: mcrecon.Error with kind")


def test_flt_max_constant():
    big = np.finfo(np.float32).max
    for value in (big, -big):
        c = np.full((12, 16, 3), value, np.float32)
        albedo = np.full((12, 16, 3), 0.3, np.float32)
        for f in ("box", "gaussian"):
            out = mcrecon.denoise(f, c, albedo=albedo, params={"demodulate": True})
            rel = np.abs(out.astype(np.float64) - float(value)) / float(big)
            assert rel.max() < 1e-3, f"{f}: a constant {value} came back as {out.min()}..{out.max()}"
    print("FLT_MAX constant kept through demodulation")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory(prefix="mcrecon_pyvalues_") as tmp:
        test_shared_session_from_threads()
        test_sequence_at_int_max(tmp)
        test_bad_values(tmp)
        test_flt_max_constant()
    print("OK")
