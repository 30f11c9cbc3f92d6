"""`mcrecon denoise --half`: two half buffers of one render (the sample scenes' 8-spp halves of
their 16-spp file) are filtered as their mean, with the noise from their difference. Oracles: the
box filter with step_back=false on the halves equals the box filter on their mean written by
numpy; with the step back on, the halves' variance pass is what it uses (the note says so); and
the output guard counts the second half as an input.

Run by ctest as `/usr/bin/python3 tests/python/test_cli_halves.py` with MCRECON_BIN and
MCRECON_SOURCE_DIR.
"""
import os
import shutil
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

WALL = os.path.join(tu.source_dir(), "samples", "data", "wall")
HALF0 = os.path.join(WALL, "wall_16spp_half0.exr")
HALF1 = os.path.join(WALL, "wall_16spp_half1.exr")
RGB = ["ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B"]


class HalvesCliTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_halves_")
        self.addCleanup(shutil.rmtree, self.tmp, ignore_errors=True)

    def test_the_mean_of_the_halves_is_filtered(self):
        out = os.path.join(self.tmp, "out.exr")
        # box radius 0 without the step back and the outlier step (firefly_k, on by default): the identity
        tu.run_cli("denoise", "-f", "box", "--set", "step_back=false", "--set", "firefly_k=0", "--set", "radius=0",
                   HALF0, "--half", HALF1, "-o", out)
        a = tu.read_channels(HALF0, RGB).astype(np.float64)
        b = tu.read_channels(HALF1, RGB).astype(np.float64)
        got = tu.read_channels(out, ["R", "G", "B"])
        np.testing.assert_allclose(got, (0.5 * a + 0.5 * b).astype(np.float32), rtol=0, atol=0)

    def test_the_step_back_uses_their_variance(self):
        out = os.path.join(self.tmp, "out.exr")
        p = tu.run_cli("denoise", "-f", "bilateral", "-v", HALF0, "--half", HALF1, "-o", out)
        self.assertIn("step_back (noise from the variance pass)", p.stderr)
        p = tu.run_cli("denoise", "-f", "bilateral", "-v", HALF0, "-o", out)
        self.assertNotIn("noise from the variance pass", p.stderr)

    def test_bad_halves_are_refused_naming_them(self):
        missing = os.path.join(self.tmp, "nope.exr")
        p = tu.run_cli("denoise", "-f", "box", HALF0, "--half", missing, "-o", os.path.join(self.tmp, "o.exr"),
                       check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn(missing, p.stderr)
        p = tu.run_cli("denoise", "-f", "box", HALF0, "--half", HALF0, "-o", os.path.join(self.tmp, "o.exr"),
                       check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn("is the input itself", p.stderr)
        # The second half is an input: never an output.
        copy = os.path.join(self.tmp, "half1.exr")
        shutil.copy(HALF1, copy)
        before = open(copy, "rb").read()
        p = tu.run_cli("denoise", "-f", "box", HALF0, "--half", copy, "-o", copy, check=False)
        self.assertEqual(p.returncode, 2)
        self.assertEqual(open(copy, "rb").read(), before)


if __name__ == "__main__":
    unittest.main()
