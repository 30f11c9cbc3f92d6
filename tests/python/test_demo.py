"""`mcrecon demo` end to end (the quick table; `bash setup.sh demo` runs `mcrecon report`, tested by py_test_report*): every sample scene gets a row per
filter, a side-by-side PNG whose tiles are the noisy input, each filter and the reference, and
results.json; the noisy rows agree with `mcrecon compare` run on the same files."""
import json
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402
import OpenImageIO as oiio  # noqa: E402

DATA = os.path.join(tu.source_dir(), "samples", "data")


class DemoTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out = tempfile.mkdtemp(prefix="mcrecon_demo_")
        cls.proc = tu.run_cli("demo", "--out", cls.out, timeout=900)
        with open(os.path.join(cls.out, "results.json")) as f:
            cls.rows = json.load(f)
        with open(os.path.join(DATA, "manifest.json")) as f:
            cls.scenes = json.load(f)["scenes"]
        # Per-sample filters (input "deep") run on deep scenes only; the sample scenes are flat.
        cls.filters = [f["name"] for f in tu.run_cli_json("filters", "--json")["filters"] if f["input"] != "deep"]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.out, ignore_errors=True)

    def test_every_scene_has_every_filter_and_a_png_of_matching_width(self):
        for scene in self.scenes:
            with self.subTest(scene=scene["name"]):
                rows = [r for r in self.rows if r["scene"] == scene["name"]]
                inputs = {r["input"] for r in rows if r["filter"] != "(noisy)"}
                self.assertEqual(len(inputs), 1, inputs)
                inp = inputs.pop()
                ran = [r["filter"] for r in rows if r["filter"] != "(noisy)"]
                self.assertEqual(sorted(ran), sorted(self.filters))
                png = oiio.ImageInput.open(os.path.join(self.out, "%s_%s.png" % (scene["name"], inp)))
                self.assertIsNotNone(png, oiio.geterror())
                try:
                    spec = png.spec()
                    # noisy | each filter | reference at the scene's size, 4-pixel gaps between
                    tiles = len(ran) + 2
                    self.assertEqual(spec.height, scene["height"])
                    self.assertEqual(spec.width, scene["width"] * tiles + 4 * (tiles - 1))
                finally:
                    png.close()

    def test_noisy_rows_match_compare(self):
        for scene in self.scenes:
            if scene["kind"] != "still":
                continue
            with self.subTest(scene=scene["name"]):
                row = [r for r in self.rows if r["scene"] == scene["name"] and r["filter"] == "(noisy)"
                       and r["input"] == "16spp"][0]
                got = tu.run_cli_json("compare", "--json", os.path.join(DATA, scene["reference"]),
                                      os.path.join(DATA, scene["noisy"]["16"]))
                for key in ("relmse", "psnr", "ssim"):
                    self.assertAlmostEqual(row[key], got[key], delta=1e-9 * max(1.0, abs(got[key])), msg=key)

    def test_every_metric_is_finite(self):
        for r in self.rows:
            for key in ("relmse", "psnr", "ssim"):
                self.assertIsNotNone(r[key], (r["scene"], r["filter"], key))


if __name__ == "__main__":
    unittest.main()
