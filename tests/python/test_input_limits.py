"""Limits from the input, through every front end: the CLI (info, denoise, compare), the
OpenImageIO plugin driven by the real oiiotool, and the Python module.

- a file whose header asks for more pixels than it can hold (a tiny EXR patched to claim a
  huge data window) is refused before anything is allocated: exit status 2 / mcrecon.Error /
  an oiiotool error, a message naming the file and the sizes, small peak memory;
  MCRECON_MAX_MEMORY replaces the file's bound (lower or higher);
- a FIFO, /dev/zero and /dev/urandom as input are refused, never waited on;
- thread counts: negative refused, more than the cores clamped (same bits as 0).

Every case runs in a fresh child with a 10 s timeout (a hang detector, not a timing check);
its peak memory is the child's ru_maxrss. Environment: MCRECON_BIN, MCRECON_SOURCE_DIR,
MCRECON_PLUGIN_DIR (mcrecon.imageio.so's folder), MCRECON_PYTHON_DIR (the module's folder);
the plugin and module cases are skipped when theirs is missing.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import unittest

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

HANG = 10  # seconds: a case that takes longer is a hang
SMALL_RSS_KB = 500 * 1024
OIIOTOOL = shutil.which("oiiotool") or "/usr/bin/oiiotool"
ROOM = os.path.join(tu.source_dir(), "samples", "data", "room", "room_16spp.exr")

# Runs argv[1:] and reports its exit status, output and peak memory (KB) as JSON.
MEASURE = textwrap.dedent("""
    import json, resource, subprocess, sys
    p = subprocess.run(sys.argv[1:], capture_output=True, text=True)
    print(json.dumps({"rc": p.returncode, "out": p.stdout + p.stderr,
                      "rss_kb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}))
""")


def measured(argv, env=None):
    """Runs argv in a fresh process; returns {'rc', 'out', 'rss_kb'}. Fails on a hang, after
    killing the whole process group (a reader blocked on a FIFO would outlive its parent)."""
    p = subprocess.Popen([sys.executable, "-c", MEASURE, *map(str, argv)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env, start_new_session=True)
    try:
        out, _ = p.communicate(timeout=HANG)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        raise AssertionError("hung (> %d s): %s" % (HANG, " ".join(map(str, argv))))
    return json.loads(out)


def patch_window(path, w, h, lines=16):
    """Makes an EXR claim a w x h data and display window, as a hostile file would: zeros
    pad it so the chunk offset table fits (OpenEXR opens it; the pixel data is missing).
    lines: scanlines per chunk of its compression (zip, tu.write_exr's: 16)."""
    with open(path, "rb") as f:
        data = bytearray(f.read())
    for name in (b"dataWindow", b"displayWindow"):
        key = name + b"\0box2i\0"
        at = data.find(key)
        assert at >= 0, name
        data[at + len(key) + 4:at + len(key) + 20] = np.array([0, 0, w - 1, h - 1], "<i4").tobytes()
    data += bytes((h + lines - 1) // lines * 8)
    with open(path, "wb") as f:
        f.write(bytes(data))


def small_exr(path, w=8, h=8):
    tu.write_exr(path, np.full((h, w, 4), 0.5, np.float32), ["R", "G", "B", "A"])


def module_dir():
    d = os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(tu.source_dir(), "build", "python")
    if not any(n.startswith("mcrecon.") and n.endswith(".so") for n in os.listdir(d) if os.path.isdir(d)):
        raise unittest.SkipTest("no mcrecon module in %s (set MCRECON_PYTHON_DIR)" % d)
    return d


def plugin_dir():
    d = os.environ.get("MCRECON_PLUGIN_DIR") or os.path.join(tu.source_dir(), "build", "lib")
    if not os.path.exists(os.path.join(d, "mcrecon.imageio.so")):
        raise unittest.SkipTest("no mcrecon.imageio.so in %s (set MCRECON_PLUGIN_DIR)" % d)
    return d


# Python-module calls in a child: prints {"ok": true} or the mcrecon.Error's {"kind", "msg"}.
PY_CALL = textwrap.dedent("""
    import json, sys
    sys.path.insert(0, sys.argv[1])
    import mcrecon
    try:
        exec(sys.argv[2])
        print(json.dumps({"ok": True}))
    except mcrecon.Error as e:
        print(json.dumps({"kind": e.kind, "msg": str(e)}))
""")


class LimitsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_limits_")
        self.addCleanup(shutil.rmtree, self.tmp, ignore_errors=True)
        self.env = {k: v for k, v in os.environ.items() if k != "MCRECON_MAX_MEMORY"}

    def path(self, name):
        return os.path.join(self.tmp, name)

    def hostile(self, w, h, name="huge.exr"):
        f = self.path(name)
        small_exr(f)
        patch_window(f, w, h)
        return f

    def env_with(self, **extra):
        return dict(self.env, **extra)

    # ---- the three front ends, each returning (status-ish, message, rss_kb)

    def cli(self, *args, env=None):
        r = measured([tu.mcrecon_bin(), *args], env or self.env)
        lines = [l for l in r["out"].splitlines() if l.startswith("mcrecon: ")]
        return r["rc"], (lines[-1] if lines else r["out"]), r["rss_kb"]

    def oiiotool(self, source, env=None):
        env = dict(env or self.env, OIIO_LIBRARY_PATH=plugin_dir())
        r = measured([OIIOTOOL, source + ".mcrecon?filter=box", "-o", self.path("plugin_out.exr")], env)
        return r["rc"], r["out"], r["rss_kb"]

    def module(self, code, env=None):
        r = measured([sys.executable, "-c", PY_CALL, module_dir(), code], env or self.env)
        self.assertEqual(r["rc"], 0, r["out"])
        return json.loads(r["out"].splitlines()[-1]), r["rss_kb"]

    def assert_refused_everywhere(self, source, *words, env=None):
        """CLI info/denoise/compare exit 2, the plugin fails, the module raises; all name the file and say why."""
        out = self.path("out.exr")
        for args in (["info", source], ["denoise", source, "-o", out, "-f", "box"], ["compare", source, source]):
            rc, msg, rss = self.cli(*args, env=env)
            self.assertEqual(rc, 2, "mcrecon %s: %s" % (" ".join(args), msg))
            for w in ("'%s'" % source, *words):
                self.assertIn(w, msg, "mcrecon %s" % args[0])
            self.assertLess(rss, SMALL_RSS_KB, "mcrecon %s peaked at %d MB" % (args[0], rss // 1024))
        self.assertFalse(os.path.exists(out))
        try:
            rc, msg, rss = self.oiiotool(source, env)
            self.assertNotEqual(rc, 0, msg)
            for w in ("mcrecon: error: cannot read '%s'" % source, *words):
                self.assertIn(w, msg, "oiiotool")
            self.assertLess(rss, SMALL_RSS_KB, "oiiotool peaked at %d MB" % (rss // 1024))
        except unittest.SkipTest as e:
            print("skipped the plugin:", e)
        try:
            r, rss = self.module("mcrecon.denoise_file(%r, %r, 'box')" % (source, out), env)
            self.assertNotIn("ok", r, "mcrecon.denoise_file read %s" % source)
            for w in ("'%s'" % source, *words):
                self.assertIn(w, r["msg"], "mcrecon.denoise_file")
            self.assertLess(rss, SMALL_RSS_KB, "the Python module peaked at %d MB" % (rss // 1024))
        except unittest.SkipTest as e:
            print("skipped the Python module:", e)
        self.assertFalse(os.path.exists(out))

    # ---- memory from the file

    def test_header_asking_4gb_from_a_tiny_file(self):
        # The "128 KB file makes info zero-fill 4 GB": 16384x16384x4 float under the old 32 GB cap.
        f = self.hostile(16384, 16384)
        self.assert_refused_everywhere(f, "16384x16384x4 float (4.29 GB)", "file can hold at most",
                                       "set MCRECON_MAX_MEMORY")

    def test_header_asking_160gb(self):
        # Through the plugin this made oiiotool allocate 160 GB and abort.
        f = self.hostile(100000, 100000)
        self.assert_refused_everywhere(f, "100000x100000x4 float (160 GB)", "file can hold at most")

    def write_deep(self, name, w, h, tile=None):
        """A deep RGBZ file of 2 samples a pixel (zips), tiled when `tile`; its bytes and chunk offsets."""
        src = self.path(name)
        spec = oiio.ImageSpec(w, h, 4, "float")
        spec.channelnames = ("R", "G", "B", "Z")
        spec.z_channel = 3
        spec.deep = True
        if tile:
            spec.tile_width = spec.tile_height = tile
        spec.attribute("compression", "zips")
        dd = oiio.DeepData()
        dd.init(spec)
        for p in range(w * h):
            dd.set_samples(p, 2)
        out = oiio.ImageOutput.create(src)
        self.assertTrue(out.open(src, spec) and out.write_deep_image(dd), out.geterror())
        out.close()
        rc, msg, _ = self.cli("info", src)
        self.assertEqual(rc, 0, msg)  # the file as written reads
        with open(src, "rb") as f:
            data = bytearray(f.read())
        # Walk the attributes to the header's end (an empty name); the chunk offset table follows.
        pos = 8
        while data[pos] != 0:
            name_end = data.index(0, pos)
            type_end = data.index(0, name_end + 1)
            size = int.from_bytes(data[type_end + 1:type_end + 5], "little")
            pos = type_end + 5 + size
        table = pos + 1
        return data, lambda k: int.from_bytes(data[table + 8 * k:table + 8 * k + 8], "little")

    def write_bytes(self, name, data):
        f = self.path(name)
        with open(f, "wb") as out:
            out.write(bytes(data))
        return f

    def test_deep_chunk_claiming_a_gigabyte(self):
        # Found by fuzz_read_deep: a 1 KB deep file whose chunk header claims 973 MB of packed
        # samples made OpenEXR allocate them before it found the file's end.
        data, chunk = self.write_deep("deep_ok.exr", 4, 3)
        # The first chunk's header: the scanline (4 bytes), the packed table size, the packed data size.
        first = chunk(0)
        data[first + 12:first + 20] = (973078708).to_bytes(8, "little")
        f = self.write_bytes("deep_chunk_1gb.exr", data)
        self.assert_refused_everywhere(f, "deep chunk 0 claims", "973078708")

    def test_deep_tile_chunk_claiming_a_gigabyte(self):
        # Found by fuzz_read_deep (a longer run than CI's): the same claim in a deep *tiled* file,
        # whose chunks start with the tile's four coordinates instead of a scanline.
        data, chunk = self.write_deep("deep_tiled_ok.exr", 5, 4, tile=2)
        second = chunk(1)  # 3x2 tiles: the second chunk
        # Tile coordinates (16 bytes), the packed table size (8), then the packed data size.
        data[second + 24:second + 32] = (1342177280).to_bytes(8, "little")
        f = self.write_bytes("deep_tile_chunk_1gb.exr", data)
        self.assert_refused_everywhere(f, "deep tile chunk 1 claims", "1342177280")

    def test_deep_chunk_claim_without_a_chunk_count(self):
        # Found by fuzz_read_deep: the same claim in a file whose chunkCount attribute is misnamed;
        # OpenEXR then counts the chunks from the window, and so does the check.
        data, chunk = self.write_deep("deep_nocount.exr", 4, 3)
        at = data.find(b"chunkCount\0")
        self.assertGreater(at, 0)
        data[at:at + 10] = b"chunkJount"
        first = chunk(0)
        data[first + 12:first + 20] = (1610612856).to_bytes(8, "little")
        f = self.write_bytes("deep_nocount_1gb.exr", data)
        self.assert_refused_everywhere(f, "deep chunk 0 claims", "1610612856")

    def test_wide_rows_of_mixed_channel_types(self):
        # Found by fuzz_read_frame: 379 bytes claiming one row of 1835009 pixels, R float, G uint,
        # B float (22 MB, within the budget) made OpenImageIO allocate 5.6 GB: it reads scanlines of
        # mixed channel types 256 rows at a time, however few the image has.
        src = self.path("mixed.exr")
        spec = oiio.ImageSpec(4, 1, 3, "float")
        spec.channelformats = (oiio.FLOAT, oiio.UINT, oiio.FLOAT)
        spec.attribute("compression", "none")
        out = oiio.ImageOutput.create(src)
        self.assertTrue(out.open(src, spec), out.geterror())
        self.assertTrue(out.write_image(np.zeros((1, 4, 3), np.float32)), out.geterror())
        out.close()
        rc, msg, _ = self.cli("info", src)
        self.assertEqual(rc, 0, msg)  # as written it reads
        patch_window(src, 1835009, 1, lines=1)
        self.assert_refused_everywhere(src, "rows of 1835009 pixels of mixed channel types", "256 rows at a time")

    def test_webp_header_claiming_gigabytes(self):
        # Found by fuzz_read_deep: 85 bytes named .exr holding a bare lossless WebP bitstream header
        # (0x2f, then 14 bits each of width - 1 and height - 1) that claims 9574x15486. OpenEXR
        # refuses it, OpenImageIO then tries every reader, and its WebP reader allocates the decoded
        # image (593 MB) inside open(), before any header check could run. The same claim in a
        # RIFF container's extended header (24 bits each), named .webp.
        v = (9574 - 1) | (15486 - 1) << 14
        bare = self.write_bytes("bare_webp.exr", bytes([0x2F]) + v.to_bytes(4, "little") + bytes([0x1F]) * 80)
        self.assert_refused_everywhere(bare, "its WebP header asks for 9574x15486x4 float", "file can hold at most")
        vp8x = bytearray(b"RIFF") + (22).to_bytes(4, "little") + b"WEBPVP8X" + (10).to_bytes(4, "little")
        vp8x += bytes(4) + (9574 - 1).to_bytes(3, "little") + (15486 - 1).to_bytes(3, "little")
        riff = self.write_bytes("huge.webp", vp8x)
        self.assert_refused_everywhere(riff, "its WebP header asks for 9574x15486x4 float", "file can hold at most")
        # A real WebP still reads; named .exr it is refused by OpenEXR's reader, never handed to another.
        ok = self.path("small.webp")
        r = subprocess.run([OIIOTOOL, "--pattern", "checker", "64x48", "4", "-d", "uint8", "-o", ok],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        rc, msg, _ = self.cli("info", ok)
        self.assertEqual(rc, 0, msg)
        misnamed = self.path("webp_named.exr")
        shutil.copy(ok, misnamed)
        self.assert_refused_everywhere(misnamed, "is not an OpenEXR file")

    def test_max_memory_lowers_and_raises_the_limit(self):
        legit = self.path("legit.exr")
        small_exr(legit, 256, 256)  # 1.05 MB of float pixels
        self.assert_refused_everywhere(legit, "256x256x4 float (1.05 MB)", "MCRECON_MAX_MEMORY=100K allows 100 KB",
                                       env=self.env_with(MCRECON_MAX_MEMORY="100K"))
        # 1500x1500x4 float (36 MB) from a tiny file: refused by the file's bound when the floor is
        # lower... so claim 4096x4096 (268 MB): refused by default, let through by MCRECON_MAX_MEMORY.
        f = self.hostile(4096, 4096)
        rc, msg, _ = self.cli("info", f)
        self.assertEqual(rc, 2)
        self.assertIn("can hold at most", msg)
        rc, msg, _ = self.cli("info", f, env=self.env_with(MCRECON_MAX_MEMORY="2G"))
        self.assertNotIn("can hold at most", msg)  # past the limit: what fails now is the missing pixel data
        self.assertNotIn("allows", msg)
        rc, msg, _ = self.cli("info", legit, env=self.env_with(MCRECON_MAX_MEMORY="lots"))
        self.assertEqual(rc, 2)
        self.assertIn("MCRECON_MAX_MEMORY='lots'", msg)

    def test_small_files_still_read(self):
        one = self.path("one.exr")
        small_exr(one, 1, 1)
        rc, msg, _ = self.cli("info", one)
        self.assertEqual(rc, 0, msg)
        rc, msg, _ = self.cli("denoise", ROOM, "-o", self.path("room.exr"), "-f", "box")
        self.assertEqual(rc, 0, msg)

    # ---- regular files only

    def test_fifo_is_refused_not_waited_on(self):
        fifo = self.path("pipe.exr")
        os.mkfifo(fifo)
        self.assert_refused_everywhere(fifo, "not a regular file (a FIFO)")
        # As a loose pass file too.
        rc, msg, _ = self.cli("denoise", ROOM, "-o", self.path("o.exr"), "-f", "box", "--pass", "albedo=" + fifo)
        self.assertEqual(rc, 2, msg)
        self.assertIn("'%s': not a regular file (a FIFO)" % fifo, msg)
        # And as the demo's sample manifest.
        data = self.path("data")
        os.mkdir(data)
        os.mkfifo(os.path.join(data, "manifest.json"))
        rc, msg, _ = self.cli("demo", "--samples", data)
        self.assertEqual(rc, 2, msg)
        self.assertIn("manifest.json': not a regular file (a FIFO)", msg)

    def test_devices_are_refused(self):
        for dev in ("/dev/zero", "/dev/urandom"):
            self.assert_refused_everywhere(dev, "not a regular file (a character device)")

    # ---- threads

    def test_thread_counts(self):
        out0, outmany = self.path("t0.exr"), self.path("tmany.exr")
        rc, msg, _ = self.cli("denoise", ROOM, "-o", out0, "-f", "bilateral", "--threads", "0")
        self.assertEqual(rc, 0, msg)
        rc, msg, _ = self.cli("denoise", ROOM, "-o", outmany, "-f", "bilateral", "--threads", "100000000")
        self.assertEqual(rc, 0, msg)
        names = ["R", "G", "B"]
        self.assertTrue(np.array_equal(tu.read_channels(out0, names).view(np.uint32),
                                       tu.read_channels(outmany, names).view(np.uint32)))
        for cmd in (["denoise", ROOM, "-o", self.path("n.exr"), "-f", "box"], ["compare", ROOM, ROOM]):
            rc, msg, _ = self.cli(*cmd, "--threads", "-1")
            self.assertEqual(rc, 2, msg)
            self.assertIn("--threads", msg)
            self.assertIn("expects a whole number in [0, 2147483647], got '-1'", msg)
        try:
            r, _ = self.module("mcrecon.denoise_file(%r, %r, 'box', threads=-1)" % (ROOM, self.path("p.exr")))
            self.assertEqual(r.get("kind"), "invalid_argument", r)
            self.assertIn("threads=-1: expected 0 (all cores) or a positive count", r["msg"])
            p0, pmany = self.path("p0.exr"), self.path("pmany.exr")
            r, _ = self.module("mcrecon.denoise_file(%r, %r, 'bilateral', threads=0)\n"
                               "mcrecon.denoise_file(%r, %r, 'bilateral', threads=100000)" % (ROOM, p0, ROOM, pmany))
            self.assertEqual(r, {"ok": True})
            self.assertTrue(np.array_equal(tu.read_channels(p0, names).view(np.uint32),
                                           tu.read_channels(pmany, names).view(np.uint32)))
        except unittest.SkipTest as e:
            print("skipped the Python module:", e)


if __name__ == "__main__":
    unittest.main()
