"""`mcrecon lightfield` end to end: the deep light-field file (channels, l*l samples per pixel,
header attributes), the flat reference, one seed one file, and the errors: a --spp that is
not a perfect square l*l with l in 1..16, an unknown scene, a non-.exr output (exit 2, the
typed value named, nothing written), and settings that would do nothing.
"""
import os
import shutil
import sys
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

W, H = 20, 14
CHANNELS = {"R", "G", "B", "lf.y1", "lf.y2", "lf.smin", "lf.smax", "lf.e1x", "lf.e1y", "lf.e2x", "lf.e2y",
            "Z", "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z"}


def read_deep(path):
    """(spec, {channel: array [pixel, sample]}): every pixel must hold the same sample count."""
    inp = oiio.ImageInput.open(path)
    assert inp is not None, oiio.geterror()
    try:
        spec = inp.spec()
        dd = inp.read_native_deep_image()
    finally:
        inp.close()
    n = spec.width * spec.height
    counts = {dd.samples(p) for p in range(n)}
    assert len(counts) == 1, counts
    k = counts.pop()
    out = {}
    for c, name in enumerate(spec.channelnames):
        out[name] = np.array([[dd.deep_value(p, c, s) for s in range(k)] for p in range(n)], dtype=np.float64)
    return spec, out


class LightFieldCli(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="mcrecon_lf_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def render(self, name, *args):
        path = os.path.join(self.dir, name)
        tu.run_cli("lightfield", "--width", W, "--height", H, *args, "-o", path)
        return path

    def test_deep_file_per_scene(self):
        for scene, effect, y_range in (("soft_shadows", "soft_shadows", 0.6), ("dof", "dof", 1.0), ("gi", "gi", 5.0)):
            with self.subTest(scene=scene):
                spec, ch = read_deep(self.render(scene + ".exr", "--scene", scene, "--spp", 9))
                self.assertTrue(spec.deep)
                self.assertEqual((spec.width, spec.height), (W, H))
                extra = set()
                if scene != "dof":  # world axes (x in world units), and the unoccluded light for soft shadows
                    extra |= {"lf.w1x", "lf.w1y", "lf.w1z", "lf.w2x", "lf.w2y", "lf.w2z"}
                if scene == "soft_shadows":
                    extra |= {"lf.modR", "lf.modG", "lf.modB"}
                self.assertEqual(set(spec.channelnames), CHANNELS | extra)
                self.assertEqual(ch["R"].shape, (W * H, 9))
                self.assertEqual(spec.getattribute("mcrecon:lightfield"), effect)
                self.assertEqual(int(spec.getattribute("mcrecon:lf_l")), 3)
                self.assertAlmostEqual(spec.getattribute("mcrecon:lf_y_range"), y_range, places=5)
                self.assertTrue(np.all(np.abs(ch["lf.y1"]) <= y_range) and np.all(np.abs(ch["lf.y2"]) <= y_range))
                self.assertTrue(np.all(ch["lf.smin"] <= ch["lf.smax"]))
                self.assertTrue(np.all(np.isfinite(ch["R"])) and np.all(ch["R"] >= 0))
                self.assertGreater(np.count_nonzero(ch["lf.smax"][:, 0] != ch["lf.smin"][:, 0]), 0,
                                   "some pixel sees more than one slope")
                n = np.sqrt(ch["N.X"] ** 2 + ch["N.Y"] ** 2 + ch["N.Z"] ** 2)
                np.testing.assert_allclose(n, 1, atol=1e-5)

    def test_same_seed_same_file(self):
        a = read_deep(self.render("a.exr", "--scene", "dof", "--spp", 4, "--seed", 5, "-j", 1))[1]
        b = read_deep(self.render("b.exr", "--scene", "dof", "--spp", 4, "--seed", 5, "-j", 2))[1]
        c = read_deep(self.render("c.exr", "--scene", "dof", "--spp", 4, "--seed", 6))[1]
        for name in CHANNELS:
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)
        self.assertFalse(np.array_equal(a["lf.y1"], c["lf.y1"]), "another seed, other jitters")

    def test_reference_agrees_with_the_samples(self):
        # The Gaussian-weighted mean of 256 samples per pixel against the 32x32 reference.
        path = self.render("ss_ref.exr", "--scene", "soft_shadows", "--reference")
        ref = oiio.ImageBuf(path)
        self.assertFalse(ref.spec().deep)
        self.assertEqual(ref.spec().nchannels, 3)
        ref = ref.get_pixels(oiio.FLOAT).reshape(H * W, 3)
        ch = read_deep(self.render("ss256.exr", "--scene", "soft_shadows", "--spp", 256))[1]
        w = np.exp(-(ch["lf.y1"] ** 2 + ch["lf.y2"] ** 2) / (2 * 0.3 ** 2))
        mean = (ch["R"] * w).sum(axis=1) / w.sum(axis=1)
        self.assertGreater(ref[:, 0].max(), 0.3, "a lit ground")
        self.assertLess(np.abs(mean - ref[:, 0]).mean(), 0.01)

    def test_bad_spp_is_refused(self):
        for spp in ("10", "0", "289", "-4", "abc", "4.0"):
            with self.subTest(spp=spp):
                out = os.path.join(self.dir, "bad_spp.exr")
                p = tu.run_cli("lightfield", "--scene", "dof", "--spp", spp, "-o", out, check=False)
                self.assertEqual(p.returncode, 2, p.stderr)
                self.assertIn("--spp", p.stderr)
                self.assertIn("perfect square", p.stderr)
                self.assertIn("got '%s'" % spp, p.stderr)
                self.assertFalse(os.path.exists(out))

    def test_other_errors(self):
        out = os.path.join(self.dir, "err.exr")
        p = tu.run_cli("lightfield", "--scene", "caustics", "-o", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("'caustics'", p.stderr)
        self.assertIn("soft_shadows, dof, gi", p.stderr)
        p = tu.run_cli("lightfield", "--scene", "dof", "-o", os.path.join(self.dir, "x.png"), check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("x.png", p.stderr)
        # Settings that would do nothing: --spp with --reference, --reference-spp without it.
        p = tu.run_cli("lightfield", "--scene", "dof", "--reference", "--spp", 16, "-o", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("--spp", p.stderr)
        self.assertIn("--reference", p.stderr)
        p = tu.run_cli("lightfield", "--scene", "dof", "--reference-spp", 16, "-o", out, check=False)
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("--reference-spp", p.stderr)
        self.assertEqual([f for f in os.listdir(self.dir) if "mcrecon-tmp" in f or f in ("err.exr", "x.png")], [])


if __name__ == "__main__":
    unittest.main()
