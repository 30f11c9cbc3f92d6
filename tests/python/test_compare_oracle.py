"""`mcrecon compare REF IMG --json` against an independent numpy implementation of the metrics.

The numpy side is written differently from the C++ core on purpose: SSIM uses a full 2D 11x11
window over an np.pad(mode="reflect") image (reflect-101) instead of separable row/column passes,
and every mean is taken by numpy over whole arrays. Agreement required: 1e-6 relative.
"""
import math
import os
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

REL_TOL = 1e-6
ABS_TOL = 1e-12  # for metrics that are exactly 0
COMBINED = ("ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B")


# ---------------------------------------------------------------- numpy oracle


def _rgb(img):
    """First three channels in float64, non-finite values replaced by 0."""
    img = np.asarray(img, dtype=np.float64)[:, :, :3]
    return np.where(np.isfinite(img), img, 0.0)


def oracle_rmse(ref, img):
    r, x = _rgb(ref), _rgb(img)
    return float(np.sqrt(np.mean(np.square(x - r))))


def oracle_relmse(ref, img):
    r, x = _rgb(ref), _rgb(img)
    return float(np.mean(np.square(x - r) / (np.square(r) + 0.01)))


def oracle_psnr(ref, img):
    """None stands for +infinity (identical clamped images), as in the CLI's JSON."""
    r, x = np.clip(_rgb(ref), 0.0, 1.0), np.clip(_rgb(img), 0.0, 1.0)
    mse = float(np.mean(np.square(x - r)))
    return None if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def _window_2d():
    d = np.arange(11, dtype=np.float64) - 5.0
    dy, dx = np.meshgrid(d, d, indexing="ij")
    k = np.exp(-(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5))
    return k / k.sum()


def _local_mean(plane, kernel):
    """Gaussian-weighted local mean: 2D correlation over a reflect-101 padded plane."""
    padded = np.pad(plane, 5, mode="reflect")  # numpy's "reflect" does not repeat the edge
    windows = np.lib.stride_tricks.sliding_window_view(padded, kernel.shape)
    return np.einsum("ijkl,kl->ij", windows, kernel)


def oracle_ssim(ref, img):
    c1, c2 = (0.01 * 1.0) ** 2, (0.03 * 1.0) ** 2
    kernel = _window_2d()
    r, x = np.clip(_rgb(ref), 0.0, 1.0), np.clip(_rgb(img), 0.0, 1.0)
    per_channel = []
    for c in range(3):
        a, b = r[:, :, c], x[:, :, c]
        mu_a, mu_b = _local_mean(a, kernel), _local_mean(b, kernel)
        var_a = _local_mean(a * a, kernel) - mu_a ** 2
        var_b = _local_mean(b * b, kernel) - mu_b ** 2
        cov = _local_mean(a * b, kernel) - mu_a * mu_b
        ssim_map = ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / (
            (mu_a ** 2 + mu_b ** 2 + c1) * (var_a + var_b + c2))
        per_channel.append(ssim_map.mean())
    return float(np.mean(per_channel))


def oracle_metrics(ref, img):
    return {"rmse": oracle_rmse(ref, img), "relmse": oracle_relmse(ref, img),
            "psnr": oracle_psnr(ref, img), "ssim": oracle_ssim(ref, img)}


# ---------------------------------------------------------------- tests


class OracleSelfTest(unittest.TestCase):
    """The oracle itself against closed forms, so that a wrong oracle cannot hide a wrong CLI."""

    def test_closed_forms(self):
        ref = np.full((6, 9, 3), 0.25)
        img = np.full((6, 9, 3), 0.75)
        self.assertAlmostEqual(oracle_rmse(ref, img), 0.5, places=12)
        self.assertAlmostEqual(oracle_relmse(ref, img), 0.25 / (0.0625 + 0.01), places=12)
        self.assertAlmostEqual(oracle_psnr(ref, img), -10 * math.log10(0.25), places=9)
        expected = (2 * 0.25 * 0.75 + 1e-4) / (0.25 ** 2 + 0.75 ** 2 + 1e-4)
        self.assertAlmostEqual(oracle_ssim(ref, img), expected, places=12)
        self.assertIsNone(oracle_psnr(ref, ref))
        self.assertAlmostEqual(oracle_ssim(img, img), 1.0, places=12)

    def test_clamping_and_non_finite(self):
        self.assertIsNone(oracle_psnr(np.ones((3, 3, 3)), np.full((3, 3, 3), 4.0)))
        self.assertAlmostEqual(oracle_rmse(np.ones((3, 3, 3)), np.full((3, 3, 3), 4.0)), 3.0)
        bad = np.full((2, 2, 3), np.nan)
        bad[0, 0, 1] = np.inf
        self.assertEqual(oracle_rmse(np.zeros((2, 2, 3)), bad), 0.0)

    def test_reflect_101_padding(self):
        # reflect-101, reflecting again for planes narrower than the window.
        self.assertEqual(list(np.pad(np.arange(3), 5, mode="reflect")),
                         [1, 0, 1, 2, 1, 0, 1, 2, 1, 0, 1, 2, 1])
        self.assertEqual(list(np.pad(np.arange(1), 5, mode="reflect")), [0] * 11)

    def test_ssim_window_against_loops(self):
        rng = np.random.default_rng(3)
        a, b = rng.random((4, 6, 3)), rng.random((4, 6, 3))
        kernel = _window_2d()

        def mirror(i, n):
            if n == 1:
                return 0
            while i < 0 or i >= n:
                i = -i if i < 0 else 2 * (n - 1) - i
            return i

        plane = a[:, :, 0] * b[:, :, 0]
        mean = _local_mean(plane, kernel)
        for y in range(4):
            for x in range(6):
                s = sum(kernel[j, i] * plane[mirror(y + j - 5, 4), mirror(x + i - 5, 6)]
                        for j in range(11) for i in range(11))
                self.assertAlmostEqual(mean[y, x], s, places=13)


class CompareOracleTest(unittest.TestCase):
    """The CLI's numbers against the oracle's."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="mcrecon_compare_")
        self.addCleanup(self.tmp.cleanup)

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def cli_compare(self, ref_path, img_path):
        result = tu.run_cli_json("compare", ref_path, img_path, "--json")
        self.assertIsInstance(result, dict)
        self.assertEqual(set(result), {"rmse", "relmse", "psnr", "ssim"},
                         "compare --json must print exactly rmse, relmse, psnr, ssim")
        return result

    def assert_metrics_close(self, got, expected, what):
        for key in ("rmse", "relmse", "psnr", "ssim"):
            g, e = got[key], expected[key]
            msg = "%s: %s is %r, numpy oracle says %r" % (what, key, g, e)
            if e is None:
                self.assertIsNone(g, msg)
                continue
            self.assertIsNotNone(g, msg)
            self.assertTrue(math.isclose(g, e, rel_tol=REL_TOL, abs_tol=ABS_TOL), msg)

    def check_pair(self, ref, img, what):
        ref_path, img_path = self.path("ref.exr"), self.path("img.exr")
        tu.write_exr(ref_path, ref, ("R", "G", "B"))
        tu.write_exr(img_path, img, ("R", "G", "B"))
        # The oracle sees exactly the float32 values that were written.
        expected = oracle_metrics(tu.read_channels(ref_path, ("R", "G", "B")),
                                  tu.read_channels(img_path, ("R", "G", "B")))
        self.assert_metrics_close(self.cli_compare(ref_path, img_path), expected, what)
        return expected

    def test_random_plain_rgb_exrs(self):
        rng = np.random.default_rng(20240601)
        for h, w in [(1, 1), (3, 50), (50, 3), (1, 7), (7, 1), (5, 3), (64, 48), (48, 64)]:
            with self.subTest(size="%dx%d" % (w, h)):
                ref = rng.uniform(0.0, 1.5, (h, w, 3))  # values above 1 exercise the clamp
                img = ref + rng.normal(0.0, 0.2, (h, w, 3))
                self.check_pair(ref, img, "random %dx%d" % (w, h))

    def test_identical_images(self):
        rng = np.random.default_rng(7)
        ref = rng.uniform(0.0, 2.0, (20, 30, 3))
        expected = self.check_pair(ref, ref, "identical")
        self.assertIsNone(expected["psnr"])
        self.assertAlmostEqual(expected["ssim"], 1.0, places=12)

    def test_non_finite_values(self):
        rng = np.random.default_rng(8)
        ref = rng.uniform(0.0, 1.0, (16, 12, 3))
        img = ref + rng.normal(0.0, 0.1, ref.shape)
        img[2, 3, 0] = np.nan
        img[5, 5, 1] = np.inf
        ref[7, 1, 2] = -np.inf
        expected = self.check_pair(ref, img, "non-finite")
        self.assertTrue(all(math.isfinite(v) for v in expected.values()))

    def _room_paths(self):
        room = os.path.join(tu.source_dir(), "samples", "data", "room")
        noisy, ref = os.path.join(room, "room_16spp.exr"), os.path.join(room, "room_ref.exr")
        missing = [p for p in (noisy, ref) if not os.path.exists(p)]
        if missing:
            self.skipTest("sample renders not generated yet: missing %s" % ", ".join(missing))
        return ref, noisy

    def test_blender_multilayer_samples(self):
        ref_path, noisy_path = self._room_paths()
        expected = oracle_metrics(tu.read_channels(ref_path, COMBINED),
                                  tu.read_channels(noisy_path, COMBINED))
        self.assert_metrics_close(self.cli_compare(ref_path, noisy_path), expected,
                                  "room_16spp vs room_ref (multilayer)")

    def test_a_transparent_pair_also_gets_its_alphas_error(self):
        # Film > Transparent: alpha_mse, the mean of (A - A_ref)^2, besides the four (numpy oracle).
        d = os.path.join(tu.source_dir(), "samples", "data", "product")
        ref_path, noisy_path = os.path.join(d, "product_ref.exr"), os.path.join(d, "product_16spp.exr")
        result = tu.run_cli_json("compare", ref_path, noisy_path, "--json")
        self.assertEqual(set(result), {"rmse", "relmse", "psnr", "ssim", "alpha_mse"})
        a = "ViewLayer.Combined.A"
        want = np.mean((tu.read_channels(noisy_path, [a]).astype(np.float64) -
                        tu.read_channels(ref_path, [a]).astype(np.float64)) ** 2)
        self.assertAlmostEqual(result["alpha_mse"], want, delta=1e-9 * want)
        text = tu.run_cli("compare", ref_path, noisy_path).stdout
        self.assertRegex(text, r"(?m)^alpha_mse ")

    def test_multilayer_against_plain_rgb(self):
        ref_path, noisy_path = self._room_paths()
        ref = tu.read_channels(ref_path, COMBINED)
        noisy = tu.read_channels(noisy_path, COMBINED)
        plain_path = self.path("room_16spp_rgb.exr")
        tu.write_exr(plain_path, noisy, ("R", "G", "B"))
        expected = oracle_metrics(ref, noisy)
        self.assert_metrics_close(self.cli_compare(ref_path, plain_path), expected,
                                  "room_ref (multilayer) vs room_16spp (plain RGB)")
        plain_ref_path = self.path("room_ref_rgb.exr")
        tu.write_exr(plain_ref_path, ref, ("R", "G", "B"))
        self.assert_metrics_close(self.cli_compare(plain_ref_path, noisy_path), expected,
                                  "room_ref (plain RGB) vs room_16spp (multilayer)")


if __name__ == "__main__":
    unittest.main()
