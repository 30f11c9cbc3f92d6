"""The mcrecon OpenImageIO plugin (mcrecon.imageio.so) driven by the real oiiotool and by
OpenImageIO's Python module, checked bit for bit against `mcrecon denoise`.

Run by ctest as `/usr/bin/python3 tests/plugin/test_plugin_oiio.py` with MCRECON_BIN,
MCRECON_SOURCE_DIR and MCRECON_PLUGIN_DIR (the folder holding mcrecon.imageio.so).

Covered: every non-temporal filter through the `?key=value` name, --iconfig and the output
plugin (-o:fileformatname=mcrecon) on the room sample; temporal filters over an
`oiiotool --frames 1-16` run on the anim sample (skipped when none is registered); accumulate
(`mcrecon denoise --accumulate`) over frames 1-4 of the anim sample in all three styles; the
notes (an unused setting; auto's scores and choice) as the mcreconNotes attribute, auto's choice as mcreconChosen; no hang on a corrupt EXR; a header
claiming more than its file holds refused before anything opens it;
--list-formats; errors named as the CLI names them, with a non-zero exit; a read through
OpenImageIO's Python module.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
import mcrecon_testutil as tu  # noqa: E402

RGBA = ["R", "G", "B", "A"]
SRC = tu.source_dir()
ROOM = os.path.join(SRC, "samples", "data", "room", "room_16spp.exr")
PRODUCT = os.path.join(SRC, "samples", "data", "product", "product_16spp.exr")  # Film > Transparent
FENCE_HALF0 = os.path.join(SRC, "samples", "data", "fence", "fence_16spp_half0.exr")
FENCE_HALF1 = os.path.join(SRC, "samples", "data", "fence", "fence_16spp_half1.exr")
ANIM = os.path.join(SRC, "samples", "data", "anim", "anim_1spp_####.exr")  # the CLI's pattern
ANIM_OIIO = ANIM.replace("####", "%04d")  # oiiotool's: one '#' is four digits there
OIIOTOOL = shutil.which("oiiotool") or "/usr/bin/oiiotool"


def plugin_dir():
    d = os.environ.get("MCRECON_PLUGIN_DIR") or os.path.join(SRC, "build", "lib")
    if not os.path.exists(os.path.join(d, "mcrecon.imageio.so")):
        raise unittest.SkipTest("no mcrecon.imageio.so in %s (set MCRECON_PLUGIN_DIR)" % d)
    return d


def oiiotool(*args, timeout=300):
    """Runs oiiotool with the plugin on its search path; returns the CompletedProcess."""
    env = dict(os.environ, OIIO_LIBRARY_PATH=plugin_dir())
    return subprocess.run([OIIOTOOL, *map(str, args)], capture_output=True, text=True, timeout=timeout, env=env)


def check_ok(proc):
    if proc.returncode != 0:
        raise AssertionError("oiiotool %s exited %d\n%s%s" % (" ".join(proc.args[1:]), proc.returncode,
                                                                proc.stdout, proc.stderr))


def same_bits(a, b):
    """Bit-for-bit equality (NaN == NaN when their bits are equal)."""
    a = np.ascontiguousarray(a, dtype=np.float32)
    b = np.ascontiguousarray(b, dtype=np.float32)
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def assert_same_pixels(test, got, want, what):
    a, b = tu.read_channels(got, RGBA), tu.read_channels(want, RGBA)
    if not same_bits(a, b):
        diff = np.abs(a.astype(np.float64) - b.astype(np.float64))
        test.fail("%s: plugin output differs from `mcrecon denoise` (max |diff| %g at %d pixels)"
                  % (what, np.nanmax(diff), int(np.count_nonzero(diff))))


def header_attribute(path, name):
    """A string attribute of an image's header (None when absent)."""
    inp = oiio.ImageInput.open(path)
    assert inp is not None, oiio.geterror()
    try:
        return inp.spec().getattribute(name)
    finally:
        inp.close()


def cli_error_line(proc):
    """The CLI's 'mcrecon: error: ...' line."""
    lines = [l for l in proc.stderr.splitlines() if l.startswith("mcrecon: error: ")]
    assert lines, "the CLI printed no error line:\n" + proc.stderr
    return lines[-1]


class PluginTestBase(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        plugin_dir()
        cls.filters = tu.run_cli_json("filters", "--json")["filters"]

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_plugin_")
        self.addCleanup(shutil.rmtree, self.tmp, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.tmp, name)


class TestDiscovery(PluginTestBase):
    def test_list_formats_names_mcrecon(self):
        proc = oiiotool("--list-formats", timeout=30)
        check_ok(proc)
        self.assertIn("mcrecon", proc.stdout + proc.stderr)

    def test_corrupt_exr_fails_fast_instead_of_deadlocking(self):
        # OIIO 2.4 offers a file that fails its own reader to every plugin while holding a
        # non-recursive lock; a plugin that calls OIIO for a foreign name deadlocks here.
        with open(ROOM, "rb") as f:
            head = f.read(300)
        bad = self.path("corrupt.exr")
        with open(bad, "wb") as f:
            f.write(head)  # valid magic and a part of the header, then nothing
        junk = self.path("junk.exr")
        with open(junk, "wb") as f:
            f.write(b"\x76\x2f\x31\x01" + os.urandom(500))
        for name in (bad, junk):
            try:
                proc = oiiotool("--info", "-v", name, timeout=10)
            except subprocess.TimeoutExpired:
                self.fail("oiiotool --info %s hung (> 10 s) with the plugin on the search path" % name)
            self.assertNotEqual(proc.returncode, 0, name)
            self.assertIn("error", (proc.stdout + proc.stderr).lower())
        # Our own name on a corrupt source: fast too; --info reads no pixels, so the error is
        # the mcreconError attribute there, and a read fails with it.
        try:
            proc = oiiotool("--info", "-v", bad + ".mcrecon?filter=box", timeout=10)
        except subprocess.TimeoutExpired:
            self.fail("oiiotool --info on a .mcrecon name of a corrupt EXR hung (> 10 s)")
        self.assertIn("mcreconError", proc.stdout)
        try:
            proc = oiiotool(bad + ".mcrecon?filter=box", "-o", self.path("o.exr"), timeout=10)
        except subprocess.TimeoutExpired:
            self.fail("reading a .mcrecon name of a corrupt EXR hung (> 10 s)")
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("mcrecon: error: ", proc.stdout + proc.stderr)


    def test_header_claims_past_the_file_are_refused_before_opening(self):
        # OpenEXR allocates an attribute at the size its header declares before comparing it
        # with the file: the plugin refuses that header before anything opens it, as the CLI.
        src = self.path("claim.exr")
        tu.write_exr(src, np.full((4, 4, 4), 0.5, np.float32), RGBA)
        with open(src, "rb") as f:
            data = bytearray(f.read())
        key = b"channels\0chlist\0"
        at = data.index(key) + len(key)
        data[at:at + 4] = (842019328).to_bytes(4, "little")
        with open(src, "wb") as f:
            f.write(bytes(data))
        cli = tu.run_cli("denoise", src, "-o", self.path("cli.exr"), "-f", "box", check=False)
        self.assertEqual(cli.returncode, 2, cli.stderr)
        line = cli_error_line(cli)
        self.assertIn("header attribute 'channels' claims 842019328 bytes", line)
        proc = oiiotool("--info", "-v", src + ".mcrecon?filter=box", timeout=60)
        self.assertIn("mcreconError", proc.stdout)
        self.assertIn(line, proc.stdout)
        proc = oiiotool(src + ".mcrecon?filter=box", "-o", self.path("o.exr"), timeout=60)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn(line, proc.stdout + proc.stderr)


class TestMatchesCli(PluginTestBase):
    def cli_denoise(self, filt, out, *extra, inp=ROOM):
        return tu.run_cli("denoise", inp, "-o", out, "-f", filt, *extra, check=False)

    def test_every_spatial_filter_matches_cli_bit_for_bit(self):
        spatial = [f["name"] for f in self.filters if not f.get("temporal") and f["input"] != "deep"]
        self.assertIn("box", spatial)
        for name in spatial:
            with self.subTest(filter=name):
                want = self.path("cli_%s.exr" % name)
                cli = self.cli_denoise(name, want)
                # 1. the ?key=value name
                got = self.path("rest_%s.exr" % name)
                proc = oiiotool(ROOM + ".mcrecon?filter=" + name, "-o", got)
                if cli.returncode != 0:  # the sample lacks a pass this filter needs: same error
                    self.assertNotEqual(proc.returncode, 0)
                    self.assertIn(cli_error_line(cli), proc.stdout + proc.stderr)
                    continue
                check_ok(proc)
                assert_same_pixels(self, got, want, "%s via ?filter=" % name)
                # 2. the output plugin: oiiotool hands it every channel of the input
                got = self.path("out_%s.exr" % name)
                check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", name, "-o:fileformatname=mcrecon", got))
                assert_same_pixels(self, got, want, "%s via -o:fileformatname=mcrecon" % name)
                inp = oiio.ImageInput.open(got)
                try:
                    self.assertEqual(list(inp.spec().channelnames), RGBA)
                finally:
                    inp.close()

    def test_a_transparent_renders_alpha_is_filtered_as_the_cli_does(self):
        want = self.path("cli_alpha.exr")
        check_ok(self.cli_denoise("pwaf", want, inp=PRODUCT))
        self.assertFalse(same_bits(tu.read_channels(want, ["A"]), tu.read_channels(PRODUCT, ["ViewLayer.Combined.A"])),
                         "the CLI kept the alpha")
        got = self.path("rest_alpha.exr")
        check_ok(oiiotool(PRODUCT + ".mcrecon?filter=pwaf", "-o", got))
        assert_same_pixels(self, got, want, "alpha via ?filter=")
        got = self.path("out_alpha.exr")
        check_ok(oiiotool(PRODUCT, "--attrib", "mcrecon:filter", "pwaf", "-o:fileformatname=mcrecon", got))
        assert_same_pixels(self, got, want, "alpha via -o:fileformatname=mcrecon")

    def test_half_reads_the_other_half_buffer_as_the_cli_does(self):
        want = self.path("cli_half.exr")
        check_ok(self.cli_denoise("pwaf", want, "--half", FENCE_HALF1, inp=FENCE_HALF0))
        got = self.path("rest_half.exr")
        check_ok(oiiotool(FENCE_HALF0 + ".mcrecon?filter=pwaf&half=" + FENCE_HALF1, "-o", got))
        assert_same_pixels(self, got, want, "?half=")
        proc = oiiotool(FENCE_HALF0, "--attrib", "mcrecon:filter", "pwaf", "--attrib", "mcrecon:half", FENCE_HALF1,
                        "-o:fileformatname=mcrecon", self.path("out_half.exr"))
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("input plugin", proc.stdout + proc.stderr)

    def test_output_metadata_survives_a_copy_with_the_plugin_loaded(self):
        # OIIO drops "<format>:" attributes of a known format when writing another one, so
        # with the plugin loaded a "mcrecon:" prefix would vanish in `oiiotool in -o out`.
        den = self.path("den.exr")
        tu.run_cli("denoise", ROOM, "-o", den, "-f", "box", "--set", "radius=1")
        for src, what in ((den, "CLI output"), (ROOM + ".mcrecon?filter=box&radius=1", "plugin read")):
            with self.subTest(source=what):
                copy = self.path("copy.exr")
                check_ok(oiiotool(src, "-o", copy))
                spec = oiio.ImageInput.open(copy)
                try:
                    self.assertEqual(spec.spec().get_string_attribute("mcreconFilter"), "box")
                    self.assertIn("radius=1", spec.spec().get_string_attribute("mcreconParameters"))
                finally:
                    spec.close()

    def test_cropped_input_keeps_its_data_window_in_every_front_end(self):
        crop = self.path("crop.exr")  # 100x80 pixels at (20, 30) of the 256x192 display window
        check_ok(oiiotool(ROOM, "--crop", "100x80+20+30", "-o", crop))
        want = self.path("cli.exr")
        tu.run_cli("denoise", crop, "-o", want, "-f", "box")
        got_read = self.path("read.exr")
        check_ok(oiiotool(crop + ".mcrecon?filter=box", "-o", got_read))
        got_out = self.path("out.exr")
        check_ok(oiiotool(crop, "--attrib", "mcrecon:filter", "box", "-o:fileformatname=mcrecon", got_out))
        for path in (want, got_read, got_out):
            inp = oiio.ImageInput.open(path)
            try:
                s = inp.spec()
                self.assertEqual((s.x, s.y, s.width, s.height), (20, 30, 100, 80), path)
                self.assertEqual((s.full_x, s.full_y, s.full_width, s.full_height), (0, 0, 256, 192), path)
            finally:
                inp.close()
        assert_same_pixels(self, got_read, want, "cropped input via ?filter=")
        assert_same_pixels(self, got_out, want, "cropped input via -o:fileformatname=mcrecon")

    def test_parameters_and_pass_overrides_in_all_three_styles(self):
        want = self.path("cli.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", "box", "--set", "radius=3", "--set", "demodulate=true",
                   "--pass", "albedo=ViewLayer.DiffCol", "--layer", "ViewLayer")
        got = self.path("rest.exr")
        check_ok(oiiotool(ROOM + ".mcrecon?filter=box&radius=3&demodulate=true&albedo=ViewLayer.DiffCol"
                          "&layer=ViewLayer", "-o", got))
        assert_same_pixels(self, got, want, "?key=value")
        got = self.path("iconfig.exr")
        check_ok(oiiotool("--iconfig", "mcrecon:filter", "box", "--iconfig:type=int", "mcrecon:radius", "3",
                          "--iconfig", "mcrecon:demodulate", "true", "--iconfig", "mcrecon:albedo",
                          "ViewLayer.DiffCol", "--iconfig", "mcrecon:layer", "ViewLayer",
                          ROOM + ".mcrecon", "-o", got))
        assert_same_pixels(self, got, want, "--iconfig")
        got = self.path("out.exr")
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", "box", "--attrib:type=int", "mcrecon:radius", "3",
                          "--attrib", "mcrecon:demodulate", "true", "--attrib", "mcrecon:albedo",
                          "ViewLayer.DiffCol", "-o:fileformatname=mcrecon", got))
        assert_same_pixels(self, got, want, "output plugin")
        # and the default radius differs, so the parameter did arrive
        other = self.path("r2.exr")
        check_ok(oiiotool(ROOM + ".mcrecon?filter=box", "-o", other))
        self.assertFalse(same_bits(tu.read_channels(other, RGBA), tu.read_channels(want, RGBA)))

    def test_output_plugin_keep_passes_matches_cli(self):
        want = self.path("cli.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", "box", "--keep-passes")
        got = self.path("out.exr")
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", "box", "--attrib:type=int", "mcrecon:keep_passes", "1",
                          "-o:fileformatname=mcrecon", got))
        names = list(oiio.ImageInput.open(want).spec().channelnames)
        self.assertGreater(len(names), 4)
        got_in = oiio.ImageInput.open(got)
        self.assertEqual(list(got_in.spec().channelnames), names)
        got_in.close()
        self.assertTrue(same_bits(tu.read_channels(got, names), tu.read_channels(want, names)))

    def test_typed_float_parameter_matches_cli(self):
        # gaussian's sigma changes every pixel of the room sample; 1.7 is not a float32 value, so
        # the plugin must turn oiiotool's float attribute back into the text the CLI parses.
        name, param, value = "gaussian", "sigma", "1.7"
        spec = {p["name"]: p for f in self.filters if f["name"] == name for p in f["parameters"]}[param]
        self.assertEqual(spec["type"], "float")
        self.assertNotEqual(float(value), spec["default"])
        want = self.path("cli.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", name, "--set", "%s=%s" % (param, value))
        default = self.path("cli_default.exr")
        tu.run_cli("denoise", ROOM, "-o", default, "-f", name)
        self.assertFalse(same_bits(tu.read_channels(want, RGBA), tu.read_channels(default, RGBA)),
                         "%s=%s gives the default's pixels: the test would not see a dropped value" % (param, value))
        got = self.path("iconfig.exr")
        check_ok(oiiotool("--iconfig", "mcrecon:filter", name, "--iconfig:type=float", "mcrecon:" + param, value,
                          ROOM + ".mcrecon", "-o", got))
        assert_same_pixels(self, got, want, "%s %s=%s via --iconfig:type=float" % (name, param, value))
        got = self.path("attrib.exr")
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", name, "--attrib:type=float", "mcrecon:" + param, value,
                          "-o:fileformatname=mcrecon", got))
        assert_same_pixels(self, got, want, "%s %s=%s via --attrib:type=float" % (name, param, value))

    def test_temporal_filters_match_cli_over_a_frames_run(self):
        temporal = [f["name"] for f in self.filters if f.get("temporal")]
        if not temporal:
            self.skipTest("no temporal filter is registered (mcrecon filters --json): the history rule is "
                          "covered by the plugin.PluginHistory unit tests with a fake temporal filter")
        for name in temporal:
            with self.subTest(filter=name):
                want = self.path("cli_%s_####.exr" % name)
                tu.run_cli("denoise", ANIM, "-o", want, "-f", name, "--frames", "1-16", timeout=600)
                got = self.path("plug_%s_####.exr" % name)
                check_ok(oiiotool("--frames", "1-16", ANIM_OIIO + ".mcrecon?filter=" + name, "-o",
                                  got.replace("####", "%04d"), timeout=600))
                out = self.path("out_%s_####.exr" % name)
                check_ok(oiiotool("--frames", "1-16", ANIM_OIIO, "--attrib", "mcrecon:filter", name,
                                  "-o:fileformatname=mcrecon", out.replace("####", "%04d"), timeout=600))
                for f in range(1, 17):
                    assert_same_pixels(self, got.replace("####", "%04d" % f), want.replace("####", "%04d" % f),
                                       "%s frame %d of an oiiotool --frames run (input plugin)" % (name, f))
                    assert_same_pixels(self, out.replace("####", "%04d" % f), want.replace("####", "%04d" % f),
                                       "%s frame %d of an oiiotool --frames run (output plugin)" % (name, f))
                # Out of order, history starts fresh: frame 2 read alone is not frame 2 of the run
                # (unless this filter's first frame equals its continued one, which BMFR's is not).
                alone = self.path("alone_%s.exr" % name)
                check_ok(oiiotool(ANIM_OIIO.replace("%04d", "0002") + ".mcrecon?filter=" + name, "-o", alone))
                fresh = self.path("fresh_%s.exr" % name)
                tu.run_cli("denoise", ANIM.replace("####", "0002"), "-o", fresh, "-f", name)
                assert_same_pixels(self, alone, fresh, "%s frame 2 on its own" % name)


class TestAccumulate(PluginTestBase):
    """accumulate=1 in every style equals `mcrecon denoise --accumulate` frame for frame."""
    FRAMES = range(1, 5)

    def frame(self, pattern, f):
        return pattern.replace("####", "%04d" % f)

    def test_accumulate_matches_cli_in_every_style(self):
        want = self.path("cli_####.exr")
        tu.run_cli("denoise", ANIM, "-o", want, "-f", "box", "--frames", "1-4", "--accumulate")
        plain = self.path("plain_####.exr")
        tu.run_cli("denoise", ANIM, "-o", plain, "-f", "box", "--frames", "1-4")
        for f in self.FRAMES[1:]:  # else a plugin that drops the setting would pass
            self.assertFalse(same_bits(tu.read_channels(self.frame(want, f), RGBA),
                                       tu.read_channels(self.frame(plain, f), RGBA)),
                             "frame %d: --accumulate gives the plain filter's pixels" % f)
        styles = {
            "?accumulate=1": ("--frames", "1-4", ANIM_OIIO + ".mcrecon?filter=box&accumulate=1", "-o"),
            "--iconfig mcrecon:accumulate": ("--frames", "1-4", "--iconfig", "mcrecon:filter", "box",
                                             "--iconfig:type=int", "mcrecon:accumulate", "1", ANIM_OIIO + ".mcrecon",
                                             "-o"),
            "--attrib mcrecon:accumulate (output plugin)": ("--frames", "1-4", ANIM_OIIO, "--attrib", "mcrecon:filter",
                                                            "box", "--attrib", "mcrecon:accumulate", "true",
                                                            "-o:fileformatname=mcrecon"),
        }
        for n, (style, args) in enumerate(styles.items()):
            with self.subTest(style=style):
                got = self.path("got%d_####.exr" % n)
                check_ok(oiiotool(*args, got.replace("####", "%04d")))
                for f in self.FRAMES:
                    assert_same_pixels(self, self.frame(got, f), self.frame(want, f),
                                       "box accumulate=1 frame %d (%s)" % (f, style))
                    params = header_attribute(self.frame(got, f), "mcreconParameters")
                    self.assertEqual(params, header_attribute(self.frame(want, f), "mcreconParameters"))
                    self.assertTrue(params.startswith("accumulate=true "), params)

    def test_bad_accumulate_value_is_named(self):
        for args in ((ROOM + ".mcrecon?filter=box&accumulate=maybe", "-o", self.path("o.exr")),
                     (ROOM, "--attrib", "mcrecon:filter", "box", "--attrib", "mcrecon:accumulate", "maybe",
                      "-o:fileformatname=mcrecon", self.path("o2.exr"))):
            with self.subTest(args=args[0]):
                proc = oiiotool(*args, timeout=60)
                self.assertNotEqual(proc.returncode, 0)
                self.assertIn("accumulate expects 0, 1, true or false, got 'maybe'", proc.stdout + proc.stderr)
                self.assertFalse(os.path.exists(args[-1]))


class TestNotes(PluginTestBase):
    def cli_notes(self, *args):
        """(unused settings, the run's notes) as `mcrecon denoise ROOM --verbose` prints them."""
        err = tu.run_cli("denoise", ROOM, "-o", self.path("cli.exr"), *args, "--verbose").stderr
        unused = [l[len("mcrecon: note: "):] for l in err.splitlines() if l.startswith("mcrecon: note: ")]
        prefix = "mcrecon: " + ROOM + ": "
        return unused, [l[len(prefix):] for l in err.splitlines() if l.startswith(prefix)]

    def test_unused_setting_is_the_mcrecon_notes_attribute(self):
        # firefly_k is on by default: off, firefly_radius is the unused setting.
        notes, run = self.cli_notes("-f", "box", "--set", "firefly_k=0", "--set", "firefly_radius=5")
        self.assertEqual(notes, ["firefly_radius has no effect with firefly_k=0"])
        name = ROOM + ".mcrecon?filter=box&firefly_k=0&firefly_radius=5"
        # 1. the input plugin's spec, before any pixel is read
        oiio.attribute("plugin_searchpath", plugin_dir())
        inp = oiio.ImageInput.open(name)
        self.assertIsNotNone(inp, oiio.geterror())
        try:
            self.assertEqual(inp.spec().getattribute("mcreconNotes"), notes[0])
        finally:
            inp.close()
        # 2. a file written from the input plugin's read carries it (oiiotool copies the header
        # at open, before the filter runs: the run's own notes are not there)
        read = self.path("read.exr")
        check_ok(oiiotool(name, "-o", read))
        self.assertEqual(header_attribute(read, "mcreconNotes"), notes[0])
        # 3. the output plugin's file: the unused setting first, then the run's notes
        out = self.path("out.exr")
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", "box", "--attrib:type=float", "mcrecon:firefly_k", "0",
                          "--attrib:type=int", "mcrecon:firefly_radius", "5", "-o:fileformatname=mcrecon", out))
        self.assertEqual(header_attribute(out, "mcreconNotes"), "; ".join(notes + run))
        # Without the setting only the run's notes are said.
        quiet_notes, quiet_run = self.cli_notes("-f", "box")
        self.assertEqual(quiet_notes, [])
        quiet = self.path("quiet.exr")
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", "box", "-o:fileformatname=mcrecon", quiet))
        self.assertEqual(header_attribute(quiet, "mcreconNotes"), "; ".join(quiet_run) or None)

    def test_auto_reports_its_choice(self):
        # auto's notes (scores, the filter chosen) are mcreconNotes, as `--verbose` prints them,
        # and the pixels are the chosen filter's as the CLI runs it.
        self.assertIn("auto", [f["name"] for f in self.filters])
        unused, run = self.cli_notes("-f", "auto")
        self.assertEqual(unused, [])
        chosen = [n[len("auto: chose "):].split()[0] for n in run if n.startswith("auto: chose ")]
        self.assertEqual(len(chosen), 1, run)
        want = self.path("chosen.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", chosen[0])
        # the output plugin: its header
        out = self.path("out.exr")
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", "auto", "-o:fileformatname=mcrecon", out))
        self.assertEqual(header_attribute(out, "mcreconFilter"), "auto")
        self.assertEqual(header_attribute(out, "mcreconNotes"), "; ".join(run))
        self.assertEqual(header_attribute(out, "mcreconChosen"), chosen[0])  # as the CLI's output says
        assert_same_pixels(self, out, want, "--attrib mcrecon:filter auto (auto chose %s)" % chosen[0])
        # the input plugin: the spec after the first read holds them (the filter runs there)
        read = self.path("read.exr")
        check_ok(oiiotool(ROOM + ".mcrecon?filter=auto", "-o", read))
        assert_same_pixels(self, read, want, "?filter=auto (auto chose %s)" % chosen[0])
        oiio.attribute("plugin_searchpath", plugin_dir())
        inp = oiio.ImageInput.open(ROOM + ".mcrecon?filter=auto")
        self.assertIsNotNone(inp, oiio.geterror())
        try:
            self.assertIsNotNone(inp.read_image(0, 0, 0, 4, "float"), inp.geterror())
            self.assertEqual(inp.spec().getattribute("mcreconNotes"), "; ".join(run))
            self.assertEqual(inp.spec().getattribute("mcreconChosen"), chosen[0])
        finally:
            inp.close()


class TestErrors(PluginTestBase):
    """Bad input: oiiotool exits non-zero and prints the CLI's own message."""

    def expect_cli_message(self, cli_args, *tool_args):
        cli = tu.run_cli("denoise", ROOM, "-o", self.path("cli.exr"), *cli_args, check=False)
        self.assertEqual(cli.returncode, 2, cli.stderr)
        line = cli_error_line(cli)
        proc = oiiotool(*tool_args, timeout=60)
        self.assertNotEqual(proc.returncode, 0, "oiiotool succeeded: %s" % " ".join(map(str, tool_args)))
        self.assertIn(line, proc.stdout + proc.stderr)
        return line

    def test_unknown_filter(self):
        line = self.expect_cli_message(["-f", "nosuchfilter"],
                                       ROOM + ".mcrecon?filter=nosuchfilter", "-o", self.path("o.exr"))
        self.assertIn("nosuchfilter", line)
        # --info reads no pixels: the error is in the header as mcreconError.
        proc = oiiotool("--info", "-v", ROOM + ".mcrecon?filter=nosuchfilter", timeout=60)
        self.assertIn("mcreconError", proc.stdout)
        self.assertIn(line, proc.stdout)

    def test_unknown_parameter_in_every_style(self):
        line = self.expect_cli_message(["-f", "box", "--set", "radios=3"],
                                       ROOM + ".mcrecon?filter=box&radios=3", "-o", self.path("o.exr"))
        self.assertIn("radios", line)
        self.expect_cli_message(["-f", "box", "--set", "radios=3"],
                                "--iconfig", "mcrecon:filter", "box", "--iconfig:type=int", "mcrecon:radios", "3",
                                ROOM + ".mcrecon", "-o", self.path("o.exr"))
        self.expect_cli_message(["-f", "box", "--set", "radios=3"],
                                ROOM, "--attrib", "mcrecon:filter", "box", "--attrib:type=int", "mcrecon:radios",
                                "3", "-o:fileformatname=mcrecon", self.path("o.exr"))

    def test_bad_parameter_values(self):
        for value in ("abc", "1000", "-1", "2.5", "1e20", "100000000000000000000"):
            with self.subTest(value=value):
                self.expect_cli_message(["-f", "box", "--set", "radius=" + value],
                                        ROOM + ".mcrecon?filter=box&radius=" + value, "-o", self.path("o.exr"))

    def test_typed_numbers_are_printed_readably(self):
        """An --iconfig float arrives as a number: the message shows it as the CLI would show
        that text, never a reformatted double with 9 digits or 300 of DBL_MAX."""
        line = self.expect_cli_message(["-f", "box", "--set", "radius=1e+20"],
                                       "--iconfig", "mcrecon:filter", "box", "--iconfig:type=float", "mcrecon:radius",
                                       "1e20", ROOM + ".mcrecon", "-o", self.path("o.exr"))
        self.assertIn("'1e+20'", line)
        self.assertIn("[0, 64]", line)
        self.expect_cli_message(["-f", "box", "--set", "clamp=-0.5"],
                                "--iconfig", "mcrecon:filter", "box", "--iconfig:type=float", "mcrecon:clamp", "-0.5",
                                ROOM + ".mcrecon", "-o", self.path("o.exr"))

    def test_bad_compression_on_the_output_plugin(self):
        cli = tu.run_cli("denoise", ROOM, "-o", self.path("cli.exr"), "-f", "box", "--compression", "bogus",
                         check=False)
        self.assertEqual(cli.returncode, 2, cli.stderr)
        line = cli_error_line(cli)
        self.assertIn("compression 'bogus'", line)
        self.assertIn("none, rle, zip, zips, piz, pxr24, b44, b44a, dwaa, dwab", line)
        out = self.path("o.exr")
        proc = oiiotool(ROOM, "--attrib", "mcrecon:filter", "box", "--attrib", "mcrecon:compression", "bogus",
                        "-o:fileformatname=mcrecon", out, timeout=60)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn(line, proc.stdout + proc.stderr)
        self.assertFalse(os.path.exists(out))
        self.assertEqual([n for n in os.listdir(self.tmp) if n != "cli.exr"], [])
        # A valid one reaches the file.
        check_ok(oiiotool(ROOM, "--attrib", "mcrecon:filter", "box", "--attrib", "mcrecon:compression", "piz",
                          "-o:fileformatname=mcrecon", out))
        self.assertEqual(header_attribute(out, "compression"), "piz")

    def test_missing_passes(self):
        line = self.expect_cli_message(["-f", "box", "--pass", "normal=NoSuchGroup"],
                                       ROOM + ".mcrecon?filter=box&normal=NoSuchGroup", "-o", self.path("o.exr"))
        self.assertIn("NoSuchGroup", line)
        self.expect_cli_message(["-f", "box", "--layer", "NoSuchLayer"],
                                ROOM + ".mcrecon?filter=box&layer=NoSuchLayer", "-o", self.path("o.exr"))
        # A file with no colour pass at all: the CLI's message, through both plugins.
        depth = self.path("depth.exr")
        tu.write_exr(depth, np.full((8, 8, 1), 0.5, np.float32), ["ViewLayer.Depth.Z"])
        cli = tu.run_cli("denoise", depth, "-o", self.path("cli.exr"), "-f", "box", check=False)
        self.assertEqual(cli.returncode, 2, cli.stderr)
        self.assertIn("no colour pass", cli.stderr)
        proc = oiiotool(depth + ".mcrecon?filter=box", "-o", self.path("o.exr"), timeout=60)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn(cli_error_line(cli), proc.stdout + proc.stderr)
        proc = oiiotool(depth, "--attrib", "mcrecon:filter", "box", "-o:fileformatname=mcrecon",
                        self.path("o2.exr"), timeout=60)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("no colour pass", proc.stdout + proc.stderr)
        self.assertFalse(os.path.exists(self.path("o2.exr")))

    def test_missing_source_and_malformed_names(self):
        missing = self.path("nothere.exr")
        cli = tu.run_cli("denoise", missing, "-o", self.path("cli.exr"), "-f", "box", check=False)
        proc = oiiotool(missing + ".mcrecon?filter=box", "-o", self.path("o.exr"), timeout=60)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn(cli_error_line(cli), proc.stdout + proc.stderr)
        proc = oiiotool(ROOM + ".mcrecon", "-o", self.path("o.exr"), timeout=60)  # no filter named
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("mcrecon: error: no filter given", proc.stdout + proc.stderr)
        # A query token without '=': OIIO itself refuses the name before the plugin sees it.
        proc = oiiotool(ROOM + ".mcrecon?filter=box&radius", "-o", self.path("o.exr"), timeout=60)
        self.assertNotEqual(proc.returncode, 0)
        self.assertFalse(os.path.exists(self.path("o.exr")))


class TestPythonModule(PluginTestBase):
    def test_read_filtered_image_through_openimageio_python(self):
        oiio.attribute("plugin_searchpath", plugin_dir())
        want = self.path("cli.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", "box", "--set", "radius=3")
        inp = oiio.ImageInput.open(ROOM + ".mcrecon?filter=box&radius=3")
        self.assertIsNotNone(inp, oiio.geterror())
        try:
            spec = inp.spec()
            self.assertEqual(inp.format_name(), "mcrecon")
            self.assertEqual(list(spec.channelnames), RGBA)
            self.assertEqual(spec.getattribute("mcreconFilter"), "box")
            pixels = inp.read_image(0, 0, 0, 4, "float")
        finally:
            inp.close()
        self.assertIsNotNone(pixels)
        self.assertTrue(same_bits(np.asarray(pixels).reshape(spec.height, spec.width, 4),
                                  tu.read_channels(want, RGBA)))
        # ImageBuf too, and errors come back through OIIO's error mechanism.
        buf = oiio.ImageBuf(ROOM + ".mcrecon?filter=box&radius=3")
        self.assertTrue(same_bits(buf.get_pixels(oiio.FLOAT), tu.read_channels(want, RGBA)))
        # Errors surface at the first pixel read (open() keeps them, see the README).
        bad = oiio.ImageInput.open(ROOM + ".mcrecon?filter=box&radius=99999")
        self.assertIsNotNone(bad, oiio.geterror())
        try:
            self.assertIn("radius", bad.spec().getattribute("mcreconError"))
            self.assertIsNone(bad.read_image(0, 0, 0, 4, "float"))
            self.assertIn("parameter 'radius' of filter 'box'", bad.geterror())
        finally:
            bad.close()


if __name__ == "__main__":
    unittest.main(verbosity=2)
