"""Light fields end to end (issue 18): `mcrecon lightfield` writes a light field and its
reference, `mcrecon info` reads them, `sheared`, `sheared4d` and `aaf` run through the CLI, the
Python module and the plugin (oiiotool's input mode) with the same bits, `sheared` beats the
unfiltered estimate against the reference, and every malformed light field (missing slope
channels, NaN coordinates, 0 samples, inconsistent l) is refused with exit status 2 and a message
naming the file and the fault, writing nothing.

Environment: MCRECON_BIN, MCRECON_PLUGIN_DIR, MCRECON_PYTHON_DIR."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

import mcrecon_testutil as tu

W, H = 64, 48


def rgb(path):
    buf = oiio.ImageBuf(path)
    assert not buf.has_error, buf.geterror()
    return buf.get_pixels(oiio.FLOAT)[:, :, :3]


def relmse(ref, img):
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + 1e-2)))


def read_deep(path):
    """(spec, {channel: (pixels, spp) array}) of a deep file with the same count per pixel."""
    inp = oiio.ImageInput.open(path)
    spec = inp.spec()
    dd = inp.read_native_deep_image()
    inp.close()
    n = spec.width * spec.height
    spp = dd.samples(0)
    chans = {}
    for c, name in enumerate(spec.channelnames):
        chans[name] = np.array([[dd.deep_value(p, c, s) for s in range(dd.samples(p))] for p in range(n)], np.float32) \
            if all(dd.samples(p) == spp for p in range(n)) else None
    return spec, chans


def write_deep(path, spec, chans, counts=None):
    """chans: {name: (pixels, spp)}; counts: samples per pixel (default every sample)."""
    names = list(chans)
    out_spec = oiio.ImageSpec(spec.width, spec.height, len(names), "float")
    out_spec.channelnames = tuple(names)
    out_spec.deep = True
    for a in spec.extra_attribs:
        if a.name.startswith("mcrecon:"):
            out_spec.attribute(a.name, a.value)
    dd = oiio.DeepData()
    dd.init(out_spec)
    n = spec.width * spec.height
    for p in range(n):
        k = chans[names[0]].shape[1] if counts is None else counts[p]
        dd.set_samples(p, k)
        for c, name in enumerate(names):
            for s in range(k):
                dd.set_deep_value(p, c, s, float(chans[name][p, min(s, chans[name].shape[1] - 1)]))
    out = oiio.ImageOutput.create(path)
    assert out.open(path, out_spec), out.geterror()
    assert out.write_deep_image(dd), out.geterror()
    out.close()


def expect_same_in_python_and_plugin(test, lf, cli, out):
    """`sheared` on lf through the Python module and the plugin (oiiotool's input mode) gives the
    CLI's output `cli` bit for bit."""
    sys.path.insert(0, os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(tu.source_dir(), "build", "python"))
    import mcrecon
    py = out("py.exr")
    mcrecon.Session("sheared", {}).denoise_file(lf, py)
    test.assertTrue(np.array_equal(rgb(py), rgb(cli)), "Python differs from the CLI")
    plugin = os.environ.get("MCRECON_PLUGIN_DIR") or os.path.join(tu.source_dir(), "build", "lib")
    oiiotool = shutil.which("oiiotool") or "/usr/bin/oiiotool"
    pl = out("plugin.exr")
    r = subprocess.run([oiiotool, lf + ".mcrecon?filter=sheared", "-o", pl], capture_output=True, text=True,
                       env=dict(os.environ, OIIO_LIBRARY_PATH=plugin), timeout=120)
    test.assertEqual(r.returncode, 0, r.stderr)
    test.assertTrue(np.array_equal(rgb(pl), rgb(cli)), "the plugin differs from the CLI")


class LightFieldEndToEnd(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="mcrecon_lf_")
        cls.lf = os.path.join(cls.dir, "dof.exr")
        cls.ref = os.path.join(cls.dir, "dof_ref.exr")
        size = ("--width", str(W), "--height", str(H))
        tu.run_cli("lightfield", "--scene", "dof", "--spp", "9", *size, "-o", cls.lf)
        tu.run_cli("lightfield", "--scene", "dof", "--reference", "--reference-spp", "256", *size, "-o", cls.ref)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def out(self, name):
        return os.path.join(self.dir, name)

    def test_info_reads_the_light_field(self):
        j = tu.run_cli_json("info", "--json", self.lf)
        lf = j["lightfield"]
        self.assertEqual((lf["effect"], lf["l"], lf["spp"], lf["pixels"]), ("dof", 3, 9, W * H))
        self.assertLess(lf["slope_min"], lf["slope_max"])
        can = {f["name"]: f["can_run"] for f in j["filters"]}
        self.assertTrue(can["sheared"] and can["sheared4d"] and can["aaf"], can)
        self.assertIn("light field: dof, 3x3 samples per pixel", tu.run_cli("info", self.lf).stdout)

    def test_sheared_beats_the_unfiltered_estimate_in_every_front_end(self):
        ref = rgb(self.ref)
        # The unfiltered estimate: the samples weighted by the Gaussian aperture (sigma 0.5).
        _, ch = read_deep(self.lf)
        g = np.exp(-0.5 * (ch["lf.y1"] / 0.5) ** 2) * np.exp(-0.5 * (ch["lf.y2"] / 0.5) ** 2)
        noisy = np.stack([(ch[c] * g).sum(axis=1) / g.sum(axis=1) for c in "RGB"], -1).reshape(H, W, 3)
        cli = self.out("cli.exr")
        p = tu.run_cli("denoise", "-f", "sheared", self.lf, "-o", cli, "-v")
        self.assertIn("sheared:", p.stderr)  # the note: pixels skipped, fallback
        e_in, e_sh = relmse(ref, noisy), relmse(ref, rgb(cli))
        print(f"dof {W}x{H} 9 spp: relMSE input {e_in:.5f}, sheared {e_sh:.5f}")
        self.assertLess(e_sh, 0.6 * e_in)  # 0.45x measured
        expect_same_in_python_and_plugin(self, self.lf, cli, self.out)

    def test_sheared_matches_the_brute_force_filter(self):
        a, b = self.out("sh.exr"), self.out("sh4d.exr")
        tu.run_cli("denoise", "-f", "sheared", self.lf, "-o", a)
        tu.run_cli("denoise", "-f", "sheared4d", self.lf, "-o", b)
        e = relmse(rgb(b), rgb(a))
        print(f"sheared against sheared4d: relMSE {e:.5f}")
        self.assertLessEqual(e, 0.01)

    def check_refused(self, path, words):
        out = self.out("never.exr")
        p = tu.run_cli("denoise", "-f", "sheared", path, "-o", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        for w in [os.path.basename(path)] + words:
            self.assertIn(w, p.stderr)
        self.assertFalse(os.path.exists(out))

    def test_malformed_light_fields_are_refused(self):
        spec, ch = read_deep(self.lf)
        n = W * H
        # Missing slope channels.
        no_slope = {k: v for k, v in ch.items() if k not in ("lf.smin", "lf.smax")}
        path = self.out("noslope.exr")
        write_deep(path, spec, no_slope)
        self.check_refused(path, ["lf.smin", "slope bounds"])
        # A NaN coordinate.
        nan = dict(ch)
        nan["lf.y1"] = ch["lf.y1"].copy()
        nan["lf.y1"][W + 3, 5] = np.nan
        path = self.out("nan.exr")
        write_deep(path, spec, nan)
        self.check_refused(path, ["pixel (3, 1)", "sample 5", "nan"])
        # No samples at all.
        path = self.out("empty.exr")
        write_deep(path, spec, ch, counts=[0] * n)
        self.check_refused(path, ["pixel (0, 0) has 0 samples"])
        # Inconsistent l: one pixel with 16 samples in a 3x3 light field.
        path = self.out("odd.exr")
        write_deep(path, spec, ch, counts=[16 if p == 7 else 9 for p in range(n)])
        self.check_refused(path, ["pixel (7, 0) has 16 samples", "needs exactly 9"])

    def test_a_flat_image_is_refused_by_the_light_field_filters(self):
        flat = self.out("flat.exr")
        tu.write_exr(flat, np.ones((4, 5, 3), np.float32))
        for f in ("sheared", "sheared4d", "aaf"):
            out = self.out("never.exr")
            p = tu.run_cli("denoise", "-f", f, flat, "-o", out, check=False)
            self.assertEqual(p.returncode, 2, p.stderr)
            self.assertIn("light-field", p.stderr)
            self.assertFalse(os.path.exists(out))


class SoftShadowsThroughALens(unittest.TestCase):
    """The appendix's combined effects: `--scene soft_shadows_dof` writes the lens beside the
    light, `info` shows both, and the two-stage filters give the same bits in every front end and
    beat the unfiltered estimate (the frame's flat colour, light and aperture weights)."""

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="mcrecon_lfc_")
        cls.lf = os.path.join(cls.dir, "sd.exr")
        cls.ref = os.path.join(cls.dir, "sd_ref.exr")
        size = ("--width", "48", "--height", "40")
        tu.run_cli("lightfield", "--scene", "soft_shadows_dof", "--spp", "16", *size, "-o", cls.lf)
        tu.run_cli("lightfield", "--scene", "soft_shadows_dof", "--reference", "--reference-spp", "256", *size,
                   "-o", cls.ref)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_info_shows_the_lens(self):
        lf = tu.run_cli_json("info", "--json", self.lf)["lightfield"]
        self.assertEqual((lf["effect"], lf["spp"]), ("soft_shadows+dof", 16))
        self.assertEqual((lf["lens"]["u_range"], lf["lens"]["sigma_u"]), (1.0, 0.5))
        self.assertLess(lf["lens"]["slope_min"], 0)
        self.assertGreater(lf["lens"]["slope_max"], 0)
        self.assertIn("  lens: u in [-1, 1]^2, sigma_u 0.5", tu.run_cli("info", self.lf).stdout)

    def test_every_front_end_runs_both_stages(self):
        ref = rgb(self.ref)
        flat = self.out("flat.exr")
        tu.run_cli("denoise", "-f", "box", "--set", "radius=0", self.lf, "-o", flat)
        cli = self.out("cli.exr")
        p = tu.run_cli("denoise", "-f", "sheared", self.lf, "-o", cli, "-v")
        for stage in ("sheared (light):", "sheared (lens):", "both stages"):
            self.assertIn(stage, p.stderr)
        e_in, e_sh = relmse(ref, rgb(flat)), relmse(ref, rgb(cli))
        print(f"soft shadows through a lens 48x40 16 spp: relMSE input {e_in:.5f}, sheared {e_sh:.5f}")
        self.assertLess(e_sh, 0.8 * e_in)
        expect_same_in_python_and_plugin(self, self.lf, cli, self.out)

    def out(self, name):
        return os.path.join(self.dir, name)


if __name__ == "__main__":
    unittest.main()
