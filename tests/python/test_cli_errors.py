"""The mcrecon CLI on bad input and on the normal path.

Bad input: a clear message on stderr naming the file, pass or parameter, exit status 2 (never a
signal, never 1), and nothing left in the output directory: no output file and no hidden
`.NAME.mcrecon-tmp.*` temp file.

Normal path: `denoise --filter box` on a Blender-like multilayer EXR (checked against a numpy box
filter), --keep-passes, `info --json`, sequences with --resume, an interrupted sequence run
(SIGTERM/SIGINT), --timings and `filters --json`.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

W, H = 32, 24
LAYER = "ViewLayer"
BLENDER_CHANNELS = [
    "Combined.R", "Combined.G", "Combined.B", "Combined.A",
    "Denoising Albedo.R", "Denoising Albedo.G", "Denoising Albedo.B",
    "Normal.X", "Normal.Y", "Normal.Z",
    "Position.X", "Position.Y", "Position.Z",
    "Depth.Z",
    "Vector.X", "Vector.Y", "Vector.Z", "Vector.W",
    "Denoising Normal.X", "Denoising Normal.Y", "Denoising Normal.Z",
    "Denoising Depth.Z",
]
TEMP_MARK = ".mcrecon-tmp."


def blender_channels(layer=LAYER):
    return ["%s.%s" % (layer, c) for c in BLENDER_CHANNELS]


def blender_pixels(w, h, seed):
    """Random but distinct per channel: channel k in [k, k + 1)."""
    rng = np.random.default_rng(seed)
    px = rng.random((h, w, len(BLENDER_CHANNELS)), dtype=np.float32)
    return px + np.arange(len(BLENDER_CHANNELS), dtype=np.float32)


def write_blender_exr(path, w=W, h=H, seed=0):
    px = blender_pixels(w, h, seed)
    tu.write_exr(path, px, blender_channels())
    return px


def numpy_box(rgb, r):
    """Mean over the (2r+1)^2 window clipped at the borders, in float64."""
    h, w, _ = rgb.shape
    out = np.zeros_like(rgb, dtype=np.float64)
    for y in range(h):
        for x in range(w):
            win = rgb[max(0, y - r):min(h, y + r + 1), max(0, x - r):min(w, x + r + 1)]
            out[y, x] = win.reshape(-1, rgb.shape[2]).astype(np.float64).mean(axis=0)
    return out


def listing(d):
    return sorted(os.listdir(d))


def temp_files(d):
    return [n for n in os.listdir(d) if TEMP_MARK in n]


def image_spec_and_pixels(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise AssertionError("cannot open %s: %s" % (path, oiio.geterror()))
    try:
        spec = inp.spec()
        data = inp.read_image(0, 0, 0, spec.nchannels, "float")
        if data is None:
            raise AssertionError("cannot read %s: %s" % (path, inp.geterror()))
        return spec, np.asarray(data).reshape(spec.height, spec.width, spec.nchannels)
    finally:
        inp.close()


class _TempDirCase(unittest.TestCase):
    """Each test gets `self.dir` (inputs) and `self.out` (an empty output directory)."""

    @classmethod
    def setUpClass(cls):
        cls.root = tempfile.mkdtemp(prefix="mcrecon_cli_")
        cls.inputs = os.path.join(cls.root, "in")
        os.mkdir(cls.inputs)
        cls.ml = os.path.join(cls.inputs, "ml.exr")
        cls.ml_pixels = write_blender_exr(cls.ml)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.root, ignore_errors=True)

    def setUp(self):
        self.out = tempfile.mkdtemp(prefix="out_", dir=self.root)

    def run_cli(self, *args, timeout=300):
        return tu.run_cli(*args, check=False, timeout=timeout)


class CliErrorTest(_TempDirCase):
    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        d = cls.inputs
        rng = np.random.default_rng(1)
        cls.small = os.path.join(d, "small.exr")
        tu.write_exr(cls.small, rng.random((8, 8, 3)), ["R", "G", "B"])
        cls.nocolour = os.path.join(d, "nocolour.exr")
        tu.write_exr(cls.nocolour, rng.random((H, W, 3)), ["ViewLayer.Normal.X", "ViewLayer.Normal.Y",
                                                         "ViewLayer.Normal.Z"])
        cls.text = os.path.join(d, "notes.exr")
        with open(cls.text, "w") as f:
            f.write("this is not an image\n" * 20)
        with open(cls.ml, "rb") as f:
            data = f.read()
        cls.half = os.path.join(d, "half.exr")
        with open(cls.half, "wb") as f:
            f.write(data[:len(data) // 2])
        cls.cut100 = os.path.join(d, "cut100.exr")
        with open(cls.cut100, "wb") as f:
            f.write(data[:100])
        cls.seq_dir = os.path.join(d, "seq")
        os.mkdir(cls.seq_dir)
        for f in (1, 2, 4):  # frame 3 missing
            tu.write_exr(os.path.join(cls.seq_dir, "shot_%04d.exr" % f), rng.random((8, 8, 4)))
        cls.input_listing = listing(d)

    def tearDown(self):
        # Inputs are never touched, whatever the error.
        self.assertEqual(listing(self.inputs), self.input_listing)

    def assert_user_error(self, args, mentions, out_dir=None):
        """Runs the CLI, expects exit status 2 with every string of `mentions` on stderr, and an
        output directory left as it was (no output, no temp file)."""
        out_dir = out_dir or self.out
        before = listing(out_dir)
        proc = self.run_cli(*args, timeout=120)
        cmd = "mcrecon " + " ".join(map(str, args))
        self.assertGreaterEqual(proc.returncode, 0, "%s was killed by signal %d\n%s"
                                % (cmd, -proc.returncode, proc.stderr))
        self.assertEqual(proc.returncode, 2, "%s exited %d (want 2)\nstderr:\n%s"
                         % (cmd, proc.returncode, proc.stderr))
        self.assertIn("error", proc.stderr, cmd)
        self.assertNotIn("internal error", proc.stderr, cmd)
        for m in mentions:
            self.assertIn(m, proc.stderr, "%s: message does not name %r:\n%s" % (cmd, m, proc.stderr))
        self.assertEqual(listing(out_dir), before, "%s left files behind" % cmd)
        self.assertEqual(temp_files(out_dir), [], cmd)
        return proc

    def denoise(self, inp, *extra, out=None):
        return ["denoise", inp, "-o", out or os.path.join(self.out, "out.exr"), "-f", "box", *extra]

    # -------------------------------------------------------------- unreadable input

    def test_missing_input_file(self):
        missing = os.path.join(self.inputs, "nosuch.exr")
        self.assert_user_error(self.denoise(missing), ["nosuch.exr"])
        self.assert_user_error(["info", missing], ["nosuch.exr"])

    def test_text_file_is_not_an_image(self):
        self.assert_user_error(self.denoise(self.text), ["notes.exr"])
        self.assert_user_error(["info", self.text], ["notes.exr"])

    def test_directory_as_input(self):
        self.assert_user_error(self.denoise(self.seq_dir), ["seq"])

    def test_truncated_exr_half(self):
        self.assert_user_error(self.denoise(self.half), ["half.exr"])
        self.assert_user_error(["info", self.half], ["half.exr"])
        self.assert_user_error(["info", "--json", self.half], ["half.exr"])

    def test_truncated_exr_100_bytes(self):
        self.assert_user_error(self.denoise(self.cut100), ["cut100.exr"])
        self.assert_user_error(["info", self.cut100], ["cut100.exr"])

    def test_truncated_exr_every_eighth(self):
        """Cuts at many places (header, offset table, pixel data, last byte)."""
        with open(self.ml, "rb") as f:
            data = f.read()
        cut = os.path.join(self.out, "cut.exr")
        for n in [0, 1, 8, 300] + [len(data) * k // 8 for k in range(1, 8)] + [len(data) - 1]:
            with open(cut, "wb") as f:
                f.write(data[:n])
            self.assert_user_error(self.denoise(cut, out=os.path.join(self.out, "o.exr")), ["cut.exr"])

    # -------------------------------------------------------------- passes

    def test_no_colour_pass(self):
        self.assert_user_error(self.denoise(self.nocolour), ["nocolour.exr", "colour"])

    def test_passes_of_different_sizes(self):
        self.assert_user_error(self.denoise(self.ml, "--pass", "normal=" + self.small),
                               ["small.exr", "normal", "8x8", "%dx%d" % (W, H)])
        self.assert_user_error(["info", self.ml, "--pass", "normal=" + self.small], ["small.exr"])

    def test_bad_pass_role(self):
        self.assert_user_error(self.denoise(self.ml, "--pass", "nosuchrole=x"), ["nosuchrole"])

    def test_bad_pass_group(self):
        self.assert_user_error(self.denoise(self.ml, "--pass", "normal=nosuchgroup"), ["nosuchgroup"])

    def test_bad_pass_syntax(self):
        self.assert_user_error(self.denoise(self.ml, "--pass", "normal"), ["--pass"])

    def test_pass_file_not_an_image(self):
        self.assert_user_error(self.denoise(self.ml, "--pass", "albedo=" + self.text), ["notes.exr"])

    def test_unknown_layer(self):
        self.assert_user_error(self.denoise(self.ml, "--layer", "NoSuchLayer"), ["NoSuchLayer", "ViewLayer"])

    # -------------------------------------------------------------- filter and parameters

    def test_unknown_filter(self):
        args = ["denoise", self.ml, "-o", os.path.join(self.out, "o.exr"), "-f", "nosuchfilter"]
        self.assert_user_error(args, ["nosuchfilter", "box"])

    def test_unknown_parameter(self):
        self.assert_user_error(self.denoise(self.ml, "--set", "nosuch=1"), ["nosuch", "box"])

    def test_parameter_out_of_range(self):
        for v in ("-1", "1000"):
            self.assert_user_error(self.denoise(self.ml, "--set", "radius=" + v), ["radius", v])

    def test_parameter_not_a_number(self):
        for v in ("abc", "2.5", "", "1e999"):
            self.assert_user_error(self.denoise(self.ml, "--set", "radius=" + v), ["radius"])

    def test_parameter_without_value(self):
        self.assert_user_error(self.denoise(self.ml, "--set", "radius"), ["--set"])

    def test_bad_thread_count_and_region(self):
        self.assert_user_error(self.denoise(self.ml, "-j", "-1"), [])
        self.assert_user_error(self.denoise(self.ml, "--region", "1,2,3"), ["--region"])
        self.assert_user_error(self.denoise(self.ml, "--region", "5,5,5,9"), ["--region"])
        self.assert_user_error(self.denoise(self.ml, "--region", "0,0,99999999999,4"), ["--region"])

    # -------------------------------------------------------------- output path

    def test_output_is_the_input(self):
        with open(self.ml, "rb") as f:
            original = f.read()
        sub = os.path.join(self.inputs, "seq")
        spellings = [self.ml, os.path.join(sub, "..", "ml.exr"),
                     os.path.join(self.inputs, ".", "ml.exr")]
        for out in spellings:
            self.assert_user_error(self.denoise(self.ml, out=out), ["ml.exr", "input"], out_dir=self.inputs)
        # Relative spelling from another working directory.
        proc = subprocess.run([tu.mcrecon_bin(), "denoise", "ml.exr", "-o", "./seq/../ml.exr", "-f", "box"],
                              cwd=self.inputs, capture_output=True, text=True, timeout=120)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        # A symlink to the input, either way round.
        link = os.path.join(self.out, "link.exr")
        os.symlink(self.ml, link)
        self.assert_user_error(self.denoise(self.ml, out=link), ["link.exr"])
        self.assert_user_error(self.denoise(link, out=self.ml), ["ml.exr"], out_dir=self.inputs)
        with open(self.ml, "rb") as f:
            self.assertEqual(f.read(), original, "the input was modified")

    def test_output_is_a_loose_pass_file(self):
        loose = os.path.join(self.out, "normals.exr")
        tu.write_exr(loose, np.zeros((H, W, 3)), ["R", "G", "B"])
        with open(loose, "rb") as f:
            original = f.read()
        self.assert_user_error(self.denoise(self.ml, "--pass", "normal=" + loose, out=loose), ["normals.exr", "input"])
        with open(loose, "rb") as f:
            self.assertEqual(f.read(), original, "the loose pass file was overwritten")

    def test_output_directory_missing(self):
        self.assert_user_error(self.denoise(self.ml, out=os.path.join(self.out, "nodir", "o.exr")), ["nodir"])

    def test_output_under_a_file(self):
        """A file used as a directory component: not writable even by root."""
        blocker = os.path.join(self.out, "somefile.exr")
        with open(blocker, "wb") as f:
            f.write(b"x")
        self.assert_user_error(self.denoise(self.ml, out=os.path.join(blocker, "o.exr")), ["somefile.exr"])

    def test_output_under_proc(self):
        """/proc refuses new files even to root."""
        out = "/proc/mcrecon-test-%d.exr" % os.getpid()
        proc = self.assert_user_error(self.denoise(self.ml, out=out), [out])
        self.assertFalse(os.path.exists(out))
        self.assertEqual([n for n in os.listdir("/proc") if TEMP_MARK in n], [], proc.stderr)

    def test_output_is_a_directory(self):
        os.mkdir(os.path.join(self.out, "d.exr"))
        self.assert_user_error(self.denoise(self.ml, out=os.path.join(self.out, "d.exr")), ["d.exr"])

    @unittest.skipIf(os.geteuid() == 0, "permission bits do not stop root")
    def test_output_directory_read_only(self):
        ro = os.path.join(self.out, "ro")
        os.mkdir(ro, 0o555)
        try:
            self.assert_user_error(self.denoise(self.ml, out=os.path.join(ro, "o.exr")), ["ro"], out_dir=ro)
        finally:
            os.chmod(ro, 0o755)

    # -------------------------------------------------------------- sequences

    def test_sequence_with_a_missing_frame(self):
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        self.assert_user_error(["denoise", pattern, "--frames", "1-4", "-o", os.path.join(self.out, "o_####.exr"),
                                "-f", "box"], ["shot_0003.exr"])

    def test_frames_without_a_pattern(self):
        self.assert_user_error(self.denoise(self.ml, "--frames", "1-4"), ["--frames"])

    def test_pattern_without_frames(self):
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        self.assert_user_error(["denoise", pattern, "-o", os.path.join(self.out, "o_####.exr"), "-f", "box"],
                               ["--frames"])

    def test_sequence_output_must_be_a_pattern(self):
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        self.assert_user_error(["denoise", pattern, "--frames", "1-2", "-o", os.path.join(self.out, "o.exr"),
                                "-f", "box"], ["pattern"])

    def test_bad_frame_ranges(self):
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        for r in ("4-1", "a-b", "1-", "99999999999-1", "1-99999999999"):
            self.assert_user_error(["denoise", pattern, "--frames", r, "-o", os.path.join(self.out, "o_####.exr"),
                                    "-f", "box"], ["--frames"])

    def test_frame_range_ending_at_int_max(self):
        """A valid range at the top of int: frames missing, and the frame loop must not overflow."""
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        self.assert_user_error(["denoise", pattern, "--frames", "2147483640-2147483647",
                                "-o", os.path.join(self.out, "o_####.exr"), "-f", "box"], ["shot_2147483640.exr"])

    def test_sequence_output_over_its_input(self):
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        self.assert_user_error(["denoise", pattern, "--frames", "1-2", "-o", pattern, "-f", "box"], ["input"],
                               out_dir=self.seq_dir)

    # -------------------------------------------------------------- command line

    def test_unknown_option_and_subcommand(self):
        self.assert_user_error(self.denoise(self.ml, "--nosuch-option"), ["nosuch-option"])
        self.assert_user_error(["nosuchcommand"], [])
        self.assert_user_error(["denoise", self.ml], [])  # -o and -f missing

    # -------------------------------------------------------------- bad values, readable messages

    def box_range(self, name):
        """'[min, max]' of a box parameter, from `mcrecon filters --json` (ints as ints)."""
        box = [f for f in tu.run_cli_json("filters", "--json")["filters"] if f["name"] == "box"][0]
        p = [p for p in box["parameters"] if p["name"] == name][0]
        fmt = (lambda v: "%d" % v) if p["type"] == "int" else (lambda v: "%g" % v)
        return "[%s, %s]" % (fmt(p["min"]), fmt(p["max"]))

    def test_unknown_compression_is_refused(self):
        for c in ("bogus", "zip:0", "zip:10", "piz:3", "dwaa:-1", ""):
            proc = self.assert_user_error(self.denoise(self.ml, "--compression", c), ["compression '%s'" % c])
            self.assertIn("none, rle, zip, zips, piz, pxr24, b44, b44a, dwaa, dwab", proc.stderr)

    def test_output_must_name_a_format_mcrecon_writes(self):
        for name in ("out.xyz", "out.bmp", "out", "out.exr.bak"):
            out = os.path.join(self.out, name)
            self.assert_user_error(self.denoise(self.ml, out=out),
                                   ["output '%s'" % out, "not a format mcrecon writes", ".exr", ".png"])
        pattern = os.path.join(self.seq_dir, "shot_####.exr")
        out = os.path.join(self.out, "o_####.gif")
        self.assert_user_error(["denoise", pattern, "--frames", "1-2", "-o", out, "-f", "box"],
                               ["output '%s'" % out, "'.gif'"])
        out = os.path.join(self.out, "sparse.png")  # sparse samples are data: EXR only
        self.assert_user_error(["sparsify", self.ml, "-o", out], ["output '%s'" % out, "use a .exr name"])

    def test_display_output_settings_are_checked_before_filtering(self):
        png = os.path.join(self.out, "out.png")
        self.assert_user_error(self.denoise(self.ml, "--view", "Filmc", out=png),
                               ["view 'Filmc'", "Standard, Filmic, Filmic Log, Raw, False Color"])
        self.assert_user_error(self.denoise(self.ml, "--look", "Punchy", out=png), ["look 'Punchy'"])
        self.assert_user_error(self.denoise(self.ml, "--keep-passes", out=png), ["PNG", "--keep-passes", ".exr"])
        self.assert_user_error(self.denoise(self.ml, "--bit-depth", "16", out=os.path.join(self.out, "o.jpg")),
                               ["bit depth 16", "JPEG takes 8"])
        self.assert_user_error(self.denoise(self.ml, "--bit-depth", "12", out=png), ["bit depth 12", "8 or 16"])
        self.assert_user_error(self.denoise(self.ml, "--ocio-config", "/nowhere/c.ocio", out=png), ["/nowhere/c.ocio"])

    def test_png_jpeg_tiff_are_the_view_of_the_exr_result(self):
        # A render with coverage (opaque, half, none) and smooth colour up to 2 (JPEG is lossy).
        a = np.repeat(np.array([1.0, 0.5, 0.0, 1.0])[None, :], 16, 0).repeat(8, 1)[:, :, None]
        y, x = np.mgrid[0:16, 0:32] / 31.0
        colour = np.stack([2 * x, x * y + 0.1, 0.5 * (1 - y)], 2)
        src = os.path.join(self.out, "cov.exr")
        tu.write_exr(src, np.concatenate([colour * a, a], 2), ["R", "G", "B", "A"])
        exr = os.path.join(self.out, "o.exr")
        self.assertEqual(self.run_cli(*self.denoise(src, "--set", "radius=0", out=exr)).returncode, 0)
        rgba = tu.read_channels(exr, ["R", "G", "B", "A"]).astype(np.float64)

        def srgb(linear):  # IEC 61966-2-1
            v = np.clip(linear, 0, 1)
            return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
        # PNG and TIFF keep straight alpha (the view of colour / alpha); JPEG, without alpha, the
        # image over black.
        straight = srgb(rgba[..., :3] / np.maximum(rgba[..., 3:], 1e-30))
        for name, depth, tol in (("o.png", 8, 0.5), ("o.tif", 16, 14.0), ("o.jpg", 8, 3.0)):
            out = os.path.join(self.out, name)
            proc = self.run_cli(*self.denoise(src, "--set", "radius=0", out=out))
            self.assertEqual(proc.returncode, 0, proc.stderr)
            want = srgb(rgba[..., :3]) if name.endswith("jpg") else straight
            config = oiio.ImageSpec()
            config.attribute("oiio:UnassociatedAlpha", 1)
            inp = oiio.ImageInput.open(out, config)
            spec = inp.spec()
            self.assertEqual(spec.format, "uint%d" % depth, name)
            self.assertEqual(spec.nchannels, 3 if name.endswith("jpg") else 4, name)
            codes = inp.read_image(0, 0, 0, 3, "float").astype(np.float64) * (2 ** depth - 1)
            inp.close()
            diff = np.abs(codes - want * (2 ** depth - 1))
            err = diff.mean() if name.endswith("jpg") else diff.max()  # JPEG: lossy, on average
            self.assertLessEqual(err, tol, "%s: %.2f codes off the sRGB transfer of the EXR result" % (name, err))
        filmic = os.path.join(self.out, "filmic.png")
        self.assertEqual(self.run_cli(*self.denoise(src, "--view", "Filmic", out=filmic)).returncode, 0)
        standard = oiio.ImageBuf(os.path.join(self.out, "o.png")).get_pixels(oiio.FLOAT)
        self.assertFalse(np.array_equal(standard, oiio.ImageBuf(filmic).get_pixels(oiio.FLOAT)))
        self.assertEqual(sorted(f for f in os.listdir(self.out) if TEMP_MARK in f), [])

    def test_demo_spp_level_the_samples_lack(self):
        samples = os.path.join(tu.source_dir(), "samples", "data")
        with open(os.path.join(samples, "manifest.json")) as f:
            manifest = json.load(f)
        scenes = manifest["scenes"] if isinstance(manifest, dict) else manifest
        levels = sorted({int(k) for s in scenes for k in s["noisy"]})
        out = os.path.join(self.out, "demo")
        for spp in ("3", "2048"):
            self.assert_user_error(["demo", "--samples", samples, "--spp", spp, "--out", out],
                                   ["--spp %s" % spp, ", ".join(map(str, levels))])
        self.assert_user_error(["demo", "--samples", samples, "--spp", "16", "3", "--out", out], ["--spp 3"])
        for spp in ("x", "0", "-4"):
            self.assert_user_error(["demo", "--samples", samples, "--spp", spp, "--out", out], ["--spp", "'%s'" % spp])

    def test_region_not_inside_the_image(self):
        for region in ("30,0,40,10", "0,0,32,25", "40,40,50,50", "0,23,32,25"):
            self.assert_user_error(self.denoise(self.ml, "--region", region),
                                   ["region %s is outside the %dx%d image (x in [0, %d), y in [0, %d))"
                                    % (region, W, H, W, H)])

    def test_parameter_messages_repeat_the_typed_text(self):
        rng = self.box_range("radius")
        for v in ("100000000000000000000", "1e20", "1E20", "65.0"):
            proc = self.assert_user_error(self.denoise(self.ml, "--set", "radius=" + v),
                                          ["'radius'", "'%s'" % v, rng])
            self.assertNotIn("e+20", proc.stderr)
        proc = self.assert_user_error(self.denoise(self.ml, "--set", "clamp=1e31"), ["'clamp'", "'1e31'", "[0, 1e+30]"])
        self.assertLess(len(proc.stderr), 300, proc.stderr)

    def test_command_line_errors_name_what_was_typed(self):
        commands = "commands: info, filters, denoise, compare, plan, sparsify, lightfield, report, demo"
        self.assert_user_error(["frobnicate"], ["unknown command 'frobnicate'; " + commands])
        self.assert_user_error(["frobnicate", "--filter", "box"], ["unknown command 'frobnicate'"])
        self.assert_user_error([], ["no command given; " + commands])
        for bad in ("abc", "-1", "99999999999", "1.5"):
            proc = self.assert_user_error(self.denoise(self.ml, "--threads", bad),
                                          ["--threads", "'%s'" % bad, "[0, 2147483647]"])
            self.assertNotIn("1797693", proc.stderr)
        self.assert_user_error(["sparsify", self.ml, "-o", os.path.join(self.out, "s.exr"), "--density", "5"],
                               ["--density", "'5'", "[0.0001, 1]"])
        self.assert_user_error(self.denoise(self.ml, "--nosuch-option"), ["--nosuch-option"])
        self.assert_user_error(self.denoise(self.ml, "--set"), ["--set"])


class CliDenoiseTest(_TempDirCase):
    def test_box_writes_rgba_float_with_the_alpha_filtered_alike(self):
        out = os.path.join(self.out, "den.exr")
        # The numpy oracle is the box alone: without the step back toward the input (on by default).
        proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box", "--set", "radius=1", "--set", "step_back=false")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertEqual(listing(self.out), ["den.exr"])
        spec, px = image_spec_and_pixels(out)
        self.assertEqual(list(spec.channelnames), ["R", "G", "B", "A"])
        self.assertEqual((spec.width, spec.height), (W, H))
        self.assertEqual(spec.format, oiio.TypeFloat)
        self.assertEqual(spec.alpha_channel, 3)
        want = numpy_box(self.ml_pixels[:, :, 0:3], 1)
        np.testing.assert_allclose(px[:, :, :3], want, rtol=1e-6, atol=0)
        # alpha=filter: the alpha through the same box (its values within the input's range)
        np.testing.assert_allclose(px[:, :, 3], numpy_box(self.ml_pixels[:, :, 3:4], 1)[:, :, 0], rtol=1e-6, atol=0)
        proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box", "--set", "radius=1", "--set", "alpha=keep")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        np.testing.assert_array_equal(image_spec_and_pixels(out)[1][:, :, 3], self.ml_pixels[:, :, 3])
        self.assertEqual(spec.get_string_attribute("mcreconFilter"), "box")

    def test_compression_is_written_as_asked(self):
        for c, want in (("piz", "piz"), ("ZIPS", "zips"), ("zip:9", "zip"), ("dwaa:45", "dwaa"), ("none", "none")):
            out = os.path.join(self.out, "c.exr")
            proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box", "--compression", c)
            self.assertEqual(proc.returncode, 0, proc.stderr)
            self.assertEqual(image_spec_and_pixels(out)[0].get_string_attribute("compression"), want, c)
        out = os.path.join(self.out, "upper.EXR")  # any case of .exr
        self.assertEqual(self.run_cli("denoise", self.ml, "-o", out, "-f", "box").returncode, 0)

    def test_radius_zero_is_identity(self):
        out = os.path.join(self.out, "same.exr")
        proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box", "--set", "radius=0")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        _, px = image_spec_and_pixels(out)
        np.testing.assert_array_equal(px, self.ml_pixels[:, :, 0:4])

    def test_keep_passes_carries_every_other_channel(self):
        out = os.path.join(self.out, "keep.exr")
        proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box", "--keep-passes")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        spec, px = image_spec_and_pixels(out)
        names = list(spec.channelnames)
        self.assertEqual(names[:4], ["R", "G", "B", "A"])
        carried = [c for c in blender_channels() if ".Combined." not in c]
        self.assertEqual(sorted(names[4:]), sorted(carried))
        for i, c in enumerate(blender_channels()):
            if c in carried:
                np.testing.assert_array_equal(px[:, :, names.index(c)], self.ml_pixels[:, :, i], err_msg=c)
        # Without --keep-passes only RGBA.
        out2 = os.path.join(self.out, "plain.exr")
        self.assertEqual(self.run_cli("denoise", self.ml, "-o", out2, "-f", "box").returncode, 0)
        self.assertEqual(list(image_spec_and_pixels(out2)[0].channelnames), ["R", "G", "B", "A"])
        # The kept output reads back with the same roles.
        j = tu.run_cli_json("info", "--json", out)
        self.assertEqual(j["roles"]["colour"]["channels"], ["R", "G", "B"])
        self.assertEqual(j["roles"]["normal"]["geometry"]["name"], "ViewLayer.Normal")
        self.assertEqual(j["roles"]["motion"]["name"], "ViewLayer.Vector")

    def test_info_json_reports_roles_with_channel_names(self):
        j = tu.run_cli_json("info", "--json", self.ml)
        self.assertEqual((j["width"], j["height"]), (W, H))
        self.assertFalse(j["deep"])
        self.assertEqual(j["layer"], LAYER)
        roles = j["roles"]
        p = LAYER + "."
        self.assertEqual(roles["colour"]["channels"], [p + "Combined.R", p + "Combined.G", p + "Combined.B"])
        self.assertEqual(roles["albedo"]["channels"],
                         [p + "Denoising Albedo.R", p + "Denoising Albedo.G", p + "Denoising Albedo.B"])
        self.assertEqual(roles["normal"]["channels"],
                         [p + "Denoising Normal.X", p + "Denoising Normal.Y", p + "Denoising Normal.Z"])
        self.assertEqual(roles["normal"]["geometry"]["channels"], [p + "Normal.X", p + "Normal.Y", p + "Normal.Z"])
        self.assertEqual(roles["normal"]["geometry"]["space"], "world")
        self.assertEqual(roles["position"]["channels"], [p + "Position.X", p + "Position.Y", p + "Position.Z"])
        self.assertEqual(roles["depth"]["channels"], [p + "Depth.Z"])
        self.assertEqual(roles["motion"]["channels"], [p + "Vector.X", p + "Vector.Y", p + "Vector.Z", p + "Vector.W"])
        self.assertEqual(roles["alpha"]["channels"], [p + "Combined.A"])
        box = [f for f in j["filters"] if f["name"] == "box"]
        self.assertEqual(len(box), 1)
        self.assertTrue(box[0]["can_run"])

    def test_info_json_with_pass_override(self):
        loose = os.path.join(self.out, "normals.exr")
        tu.write_exr(loose, np.zeros((H, W, 3)), ["R", "G", "B"])
        j = tu.run_cli_json("info", "--json", self.ml, "--pass", "normal=" + loose)
        self.assertEqual(j["roles"]["normal"]["source"], loose)
        self.assertNotIn("geometry", j["roles"]["normal"])

    def test_timings_print_each_stage(self):
        out = os.path.join(self.out, "t.exr")
        proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box", "--timings")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        for stage in ("read", "filter", "write", "total"):
            self.assertRegex(proc.stderr, r"%s [0-9.]+ ms" % stage)
        proc = self.run_cli("denoise", self.ml, "-o", out, "-f", "box")
        self.assertNotIn(" ms", proc.stderr)

    def test_filters_json_lists_box_with_its_parameter_table(self):
        j = tu.run_cli_json("filters", "--json")
        box = [f for f in j["filters"] if f["name"] == "box"]
        self.assertEqual(len(box), 1)
        box = box[0]
        self.assertIn("colour", box["required_passes"])
        self.assertTrue(box["nonfinite_policy"])
        params = {p["name"]: p for p in box["parameters"]}
        self.assertIn("radius", params)
        self.assertEqual(params["radius"], {"name": "radius", "type": "int", "default": 2, "min": 0, "max": 64,
                                            "help": params["radius"]["help"]})
        self.assertTrue(params["radius"]["help"])
        for p in box["parameters"]:
            for key in ("name", "type", "default", "help"):
                self.assertIn(key, p, p)
            if p["type"] in ("int", "float"):
                self.assertLessEqual(p["min"], p["default"], p)
                self.assertLessEqual(p["default"], p["max"], p)
            if p["type"] == "enum":
                self.assertIn(p["default"], p["choices"], p)


class CliSequenceTest(_TempDirCase):
    def make_sequence(self, n, w, h, prefix="shot_"):
        rng = np.random.default_rng(7)
        d = tempfile.mkdtemp(prefix="seq_", dir=self.root)
        for f in range(1, n + 1):
            tu.write_exr(os.path.join(d, "%s%04d.exr" % (prefix, f)), rng.random((h, w, 4), dtype=np.float32))
        return d

    def test_sequence_and_resume(self):
        d = self.make_sequence(4, 16, 12)
        out_pattern = os.path.join(self.out, "out_####.exr")
        # The box oracle is the filter's own result: the step back off.
        args = ["denoise", os.path.join(d, "shot_####.exr"), "--frames", "1-4", "-o", out_pattern, "-f", "box",
                "--set", "step_back=false"]
        proc = self.run_cli(*args)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        outs = [os.path.join(self.out, "out_%04d.exr" % f) for f in range(1, 5)]
        self.assertEqual(listing(self.out), [os.path.basename(o) for o in outs])
        for f, o in enumerate(outs, 1):
            _, src = image_spec_and_pixels(os.path.join(d, "shot_%04d.exr" % f))
            _, px = image_spec_and_pixels(o)
            np.testing.assert_allclose(px[:, :, :3], numpy_box(src[:, :, :3], 2), rtol=1e-6)
        before = {o: os.stat(o) for o in outs[:2]}
        os.remove(outs[2])
        os.remove(outs[3])
        proc = self.run_cli(*args, "--resume")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertEqual(listing(self.out), [os.path.basename(o) for o in outs])
        for o in outs[:2]:  # untouched: same inode (a rewrite renames a new file in) and mtime
            st = os.stat(o)
            self.assertEqual((st.st_ino, st.st_mtime_ns), (before[o].st_ino, before[o].st_mtime_ns), o)
            self.assertIn("skip " + o, proc.stderr)
        for o in outs[2:]:
            self.assertNotIn("skip " + o, proc.stderr)
            self.assertEqual(image_spec_and_pixels(o)[0].nchannels, 4)
        self.assertIn("2 written, 2 already done", proc.stderr)

    def test_resume_redoes_a_truncated_output(self):
        d = self.make_sequence(3, 16, 12)
        args = ["denoise", os.path.join(d, "shot_####.exr"), "--frames", "1-3",
                "-o", os.path.join(self.out, "out_####.exr"), "-f", "box"]
        self.assertEqual(self.run_cli(*args).returncode, 0)
        outs = [os.path.join(self.out, "out_%04d.exr" % f) for f in (1, 2, 3)]
        _, want = image_spec_and_pixels(outs[1])
        with open(outs[1], "rb") as f:
            data = f.read()
        with open(outs[1], "wb") as f:  # what a SIGKILL or a full disk might leave
            f.write(data[:len(data) // 2])
        before = os.stat(outs[0])
        proc = self.run_cli(*args, "--resume")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("redo %s (unreadable: " % outs[1], proc.stderr)
        self.assertIn("1 written, 2 already done", proc.stderr)
        np.testing.assert_array_equal(image_spec_and_pixels(outs[1])[1], want)  # complete again
        st = os.stat(outs[0])
        self.assertEqual((st.st_ino, st.st_mtime_ns), (before.st_ino, before.st_mtime_ns))
        self.assertEqual(temp_files(self.out), [])

    def test_printf_pattern(self):
        d = self.make_sequence(2, 8, 8)
        proc = self.run_cli("denoise", os.path.join(d, "shot_%04d.exr"), "--frames", "1-2",
                            "-o", os.path.join(self.out, "o_%02d.exr"), "-f", "box")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertEqual(listing(self.out), ["o_01.exr", "o_02.exr"])

    def interrupt(self, sig, after_outputs):
        """Starts a 30-frame run, sends `sig` once `after_outputs` outputs exist, checks what is left."""
        d = self.make_sequence(30, 512, 512)
        out_pattern = os.path.join(self.out, "out_####.exr")
        # alpha=keep: the random alpha would be filtered by a second run per frame, which only
        # doubles the time (424 s of the ASan job's 600 s limit for this file with it).
        args = [tu.mcrecon_bin(), "denoise", os.path.join(d, "shot_####.exr"), "--frames", "1-30",
                "-o", out_pattern, "-f", "box", "-j", "1", "--set", "alpha=keep"]
        proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            want = os.path.join(self.out, "out_%04d.exr" % after_outputs)
            deadline = time.monotonic() + 300
            while not os.path.exists(want) and proc.poll() is None and time.monotonic() < deadline:
                time.sleep(0.002)  # polling only; nothing depends on how long this waits
            self.assertTrue(os.path.exists(want), "no output appeared")
            proc.send_signal(sig)
            _, err = proc.communicate(timeout=120)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        self.assertEqual(proc.returncode, -sig, "the run was not interrupted by the signal:\n" + err)
        left = listing(self.out)
        self.assertEqual(temp_files(self.out), [], left)
        self.assertLess(len(left), 30)
        self.assertGreaterEqual(len(left), after_outputs)
        # Only whole outputs, frames 1..k in order, each readable.
        self.assertEqual(left, ["out_%04d.exr" % f for f in range(1, len(left) + 1)])
        for n in left:
            spec, px = image_spec_and_pixels(os.path.join(self.out, n))
            self.assertEqual((spec.width, spec.height, spec.nchannels), (512, 512, 4))
            self.assertTrue(np.isfinite(px).all())
        # --resume finishes the job and writes only what is missing.
        inodes = {n: os.stat(os.path.join(self.out, n)).st_ino for n in left}
        proc2 = self.run_cli(*args[1:], "--resume")
        self.assertEqual(proc2.returncode, 0, proc2.stderr)
        self.assertEqual(listing(self.out), ["out_%04d.exr" % f for f in range(1, 31)])
        for n, ino in inodes.items():
            self.assertEqual(os.stat(os.path.join(self.out, n)).st_ino, ino, n)

    def test_sigterm_leaves_only_complete_outputs(self):
        self.interrupt(signal.SIGTERM, 1)

    def test_sigint_leaves_only_complete_outputs(self):
        self.interrupt(signal.SIGINT, 2)

    def test_stale_temp_of_a_killed_run_is_removed(self):
        d = self.make_sequence(1, 8, 8)
        stale = os.path.join(self.out, ".out_0001.exr.mcrecon-tmp.999999")
        with open(stale, "w") as f:
            f.write("partial")
        proc = self.run_cli("denoise", os.path.join(d, "shot_####.exr"), "--frames", "1",
                            "-o", os.path.join(self.out, "out_####.exr"), "-f", "box")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertEqual(listing(self.out), ["out_0001.exr"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
