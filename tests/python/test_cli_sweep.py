"""The per-sample filter `sweep` (Shirley et al. 2011) end to end: a deep EXR written here in
the per-sample convention (README) is filtered by the CLI, the Python module and the plugin
(oiiotool's input mode); the result is checked pixel by pixel against a Python transcription
of the paper's Appendix A (two scales, 1 and 5, blended) run on the file's own samples, and the
three front ends must agree bit for bit. Also: `mcrecon info` on the deep file, and the errors
for flat input and a missing channel.

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

W, H, SPP = 24, 18, 8
PAPER = ("--set", "width=5", "--set", "step_back=0")
PAPER_PARAMS = {"width": 5.0, "step_back": 0.0}
LENS, FSTOP, FOCUS, SENSOR = 50.0, 0.1, 4.0, 36.0  # a strong defocus on 24 pixels


def coc(z):
    if not (0 < z < 1e9):
        return LENS * 1e-3 / FSTOP / FOCUS * (LENS / SENSOR) * W
    return LENS * 1e-3 / FSTOP * abs(z - FOCUS) / (z * FOCUS) * (LENS / SENSOR) * W


def make_samples(seed=4):
    """Per pixel: SPP samples of (R, G, B, Z, dx, dy): a near blurred object, a sharp one at the
    focus, a far blurred background."""
    rng = np.random.default_rng(seed)
    px = []
    for y in range(H):
        for x in range(W):
            s = []
            for _ in range(SPP):
                u = rng.random()
                if x + y < 12 and u < 0.6:
                    z, c = 1.1 + 0.3 * rng.random(), (2.0, 0.3, 0.2)
                elif y < 12:
                    z, c = FOCUS - 0.05 + 0.1 * rng.random(), (0.2, 0.9, 0.3) if (x // 3) % 2 else (0.1, 0.1, 0.8)
                else:
                    z, c = 50.0 + rng.random(), (0.6, 0.6, 0.6)
                noise = rng.random(3) * 0.4
                s.append([c[0] + noise[0], c[1] + noise[1], c[2] + noise[2], z, rng.random(), rng.random()])
            px.append(s)
    return px


def write_deep(path, px):
    spec = oiio.ImageSpec(W, H, 6, "float")
    spec.channelnames = ("R", "G", "B", "Z", "dx", "dy")
    spec.z_channel = 3
    spec.deep = True
    spec.attribute("compression", "zips")
    for k, v in (("lens_mm", LENS), ("fstop", FSTOP), ("focus_distance", FOCUS), ("sensor_width_mm", SENSOR)):
        spec.attribute("mcrecon:" + k, float(v))
    dd = oiio.DeepData()
    dd.init(spec)
    for p, s in enumerate(px):
        dd.set_samples(p, len(s))
        for i, v in enumerate(s):
            for c in range(6):
                dd.set_deep_value(p, c, i, float(v[c]))
    out = oiio.ImageOutput.create(path)
    assert out.open(path, spec), out.geterror()
    assert out.write_deep_image(dd), out.geterror()
    out.close()


def appendix_a(px, x0, y0):
    """Appendix A as printed (qsort by z, the two coverages), blend clamp((D - 1) / 4) (the
    project's ramp, reaching 1 at the wide box's width; the paper's / 5 ends at 6)."""
    s = []
    for y in range(max(0, y0 - 2), min(H, y0 + 3)):
        for x in range(max(0, x0 - 2), min(W, x0 + 3)):
            for v in px[y * W + x]:
                s.append((v[3], x + v[4] - (x0 + 0.5), y + v[5] - (y0 + 0.5), coc(v[3]), v[:3]))
    s.sort(key=lambda t: t[0])
    box = lambda t, r: 0.5 / r if abs(t) < r else 0.0
    ns = float(SPP)
    cov_1 = cov_5 = cov = 0.0
    total = np.zeros(3)
    for z, sx, sy, D, colour in s:
        w_1 = (1 / ns) * box(sx, 0.5) * box(sy, 0.5)
        w_5 = (1 / ns) * box(sx, 2.5) * box(sy, 2.5)
        blend = min(max((D - 1) / 4, 0.0), 1.0)
        w = blend * (w_5 * (1 - cov_1) + w_1 * cov_1)
        cov_5 += blend * (w_5 * (1 - cov_1))
        w += (1 - blend) * (w_1 * (1 - cov_5) + w_5 * cov_5)
        cov_1 += (1 - blend) * (w_1 * (1 - cov_5))
        cov += w
        total += w * np.array(colour)
    return total / cov


def rgb(path):
    buf = oiio.ImageBuf(path)
    assert not buf.has_error, buf.geterror()
    return buf.get_pixels(oiio.FLOAT)[:, :, :3]


class SweepEndToEnd(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="mcrecon_sweep_")
        cls.px = make_samples()
        cls.deep = os.path.join(cls.dir, "defocus.exr")
        write_deep(cls.deep, cls.px)
        cls.out = os.path.join(cls.dir, "cli.exr")
        # The paper's algorithm (Appendix A: scales 1 and 5), without the step back.
        cls.proc = tu.run_cli("denoise", "-f", "sweep", *PAPER, cls.deep, "-o", cls.out, "-v")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_cli_matches_appendix_a(self):
        got = rgb(self.out)
        worst = 0.0
        for (x, y) in [(0, 0), (3, 4), (6, 6), (11, 2), (12, 9), (20, 5), (5, 14), (23, 17), (15, 11), (9, 12)]:
            want = appendix_a(self.px, x, y)
            worst = max(worst, float(np.abs(got[y, x] - want).max()))
        print(f"sweep vs Appendix A on 10 pixels: max difference {worst:.2e}")
        self.assertLess(worst, 1e-4)
        self.assertIn("sweep:", self.proc.stderr)  # the note: pixels sorted
        # The filter reconstructs: it differs from the per-pixel sample mean where things blur.
        mean = np.array([np.mean(np.array(s)[:, :3], axis=0) for s in self.px]).reshape(H, W, 3)
        self.assertGreater(float(np.abs(got - mean).max()), 0.05)

    def test_python_module_and_plugin_agree_with_the_cli(self):
        sys.path.insert(0, os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(tu.source_dir(), "build", "python"))
        import mcrecon
        py_out = os.path.join(self.dir, "py.exr")
        mcrecon.Session("sweep", PAPER_PARAMS).denoise_file(self.deep, py_out)
        self.assertTrue(np.array_equal(rgb(py_out), rgb(self.out)), "Python differs from the CLI")
        plugin = os.environ.get("MCRECON_PLUGIN_DIR") or os.path.join(tu.source_dir(), "build", "lib")
        oiiotool = shutil.which("oiiotool") or "/usr/bin/oiiotool"
        pl_out = os.path.join(self.dir, "plugin.exr")
        p = subprocess.run([oiiotool, self.deep + ".mcrecon?filter=sweep&width=5&step_back=0", "-o", pl_out], capture_output=True,
                           text=True, env=dict(os.environ, OIIO_LIBRARY_PATH=plugin), timeout=120)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertTrue(np.array_equal(rgb(pl_out), rgb(self.out)), "the plugin differs from the CLI")

    def test_write_deep_makes_the_same_file(self):
        """mcrecon.write_deep (what the Blender export uses) writes the samples as the convention
        says: sweep on it gives the CLI's result on the file written here, bit for bit."""
        sys.path.insert(0, os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(tu.source_dir(), "build", "python"))
        import mcrecon
        a = np.array(self.px, np.float32).reshape(H, W, SPP, 6).transpose(2, 3, 0, 1)  # (sample, channel, y, x)
        path = os.path.join(self.dir, "written.exr")
        mcrecon.write_deep(path, {n: a[:, c] for c, n in enumerate(("R", "G", "B", "Z", "dx", "dy"))},
                           {"mcrecon:lens_mm": LENS, "mcrecon:fstop": FSTOP, "mcrecon:focus_distance": FOCUS,
                            "mcrecon:sensor_width_mm": SENSOR})
        out = os.path.join(self.dir, "written_out.exr")
        tu.run_cli("denoise", "-f", "sweep", *PAPER, path, "-o", out)
        self.assertTrue(np.array_equal(rgb(out), rgb(self.out)))
        self.assertEqual(tu.run_cli_json("info", "--json", path)["deep_buffer"]["samples"], W * H * SPP)
        self.assertFalse([f for f in os.listdir(self.dir) if "mcrecon-tmp" in f])
        with self.assertRaises(mcrecon.Error):
            mcrecon.write_deep(os.path.join(self.dir, "bad.exr"), {"R": a[:, 0], "G": a[:2, 1]})

    def test_info_reports_the_deep_buffer(self):
        j = tu.run_cli_json("info", "--json", self.deep)
        d = j["deep_buffer"]
        self.assertEqual(d["samples"], W * H * SPP)
        self.assertEqual((d["per_pixel_min"], d["per_pixel_max"], d["empty_pixels"]), (SPP, SPP, 0))
        self.assertEqual(d["convention_found"], ["R", "G", "B", "Z", "dx", "dy"])
        self.assertEqual(float(d["camera"]["mcrecon:fstop"]), FSTOP)
        sweep = [f for f in j["filters"] if f["name"] == "sweep"][0]
        self.assertTrue(sweep["can_run"], sweep)
        text = tu.run_cli("info", self.deep).stdout
        self.assertIn("per-sample convention: found R G B Z dx dy", text)

    def test_flat_input_and_missing_channel_are_refused(self):
        flat = os.path.join(self.dir, "flat.exr")
        tu.write_exr(flat, np.ones((4, 5, 3), np.float32))
        out = os.path.join(self.dir, "never.exr")
        p = tu.run_cli("denoise", "-f", "sweep", flat, "-o", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("deep", p.stderr)
        self.assertIn("flat.exr", p.stderr)
        self.assertFalse(os.path.exists(out))
        j = tu.run_cli_json("info", "--json", flat)
        sweep = [f for f in j["filters"] if f["name"] == "sweep"][0]
        self.assertEqual(sweep["missing"], ["per-sample (deep) input"])
        # A deep file without Z.
        nz = os.path.join(self.dir, "noz.exr")
        spec = oiio.ImageSpec(2, 2, 3, "float")
        spec.channelnames = ("R", "G", "B")
        spec.deep = True
        dd = oiio.DeepData()
        dd.init(spec)
        for p_ in range(4):
            dd.set_samples(p_, 2)
        o = oiio.ImageOutput.create(nz)
        self.assertTrue(o.open(nz, spec) and o.write_deep_image(dd), o.geterror())
        o.close()
        p = tu.run_cli("denoise", "-f", "sweep", nz, "-o", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("'Z'", p.stderr)
        self.assertIn("noz.exr", p.stderr)


if __name__ == "__main__":
    unittest.main()
