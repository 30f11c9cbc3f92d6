"""`mcrecon report` over every sample scene (what `bash setup.sh demo` runs, without the parameter
sweeps, the OpenCV peer and the large scaling sizes, to stay within CI's time): every filter of the
registry and `auto` appear, each on the scenes whose input it takes; every scene has its section,
pictures and levels in the page; the scaling section has every filter."""
import json
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402
import test_report_page as page  # noqa: E402


class ReportSamplesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="mcrecon_report_samples_")
        cls.proc = tu.run_cli("report", "-o", cls.tmp, "--no-sweeps", "--no-builtin-peers", "--scaling-min", "64",
                              "--scaling-max", "128", "-j", "2", timeout=1500)
        with open(os.path.join(cls.tmp, "results.json")) as f:
            cls.results = json.load(f)
        with open(os.path.join(cls.tmp, "report.html")) as f:
            cls.html = f.read()
        cls.filters = [f["name"] for f in tu.run_cli_json("filters", "--json")["filters"]]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_every_filter_and_auto_appear(self):
        self.assertIn("auto", self.filters)
        ran = {r["filter"] for s in self.results["scenes"] for r in s["runs"] if r["default"]}
        self.assertEqual(ran, set(self.filters))
        kinds = {s["kind"] for s in self.results["scenes"]}
        self.assertEqual(kinds, {"still", "sequence", "deep", "lightfield"})
        for s in self.results["scenes"]:
            with self.subTest(scene=s["id"]):
                # each filter either ran or says why not
                named = {r["filter"] for r in s["runs"]} | {k["filter"] for k in s["skipped"]}
                self.assertEqual(named, set(self.filters))
                self.assertIn("auto", {r["filter"] for r in s["runs"]})
                self.assertTrue(any(l["is_input"] for l in s["levels"]))
                for r in s["runs"]:
                    self.assertNotIn("error", r)
                    self.assertEqual(r["timing"] if "timing" in r else s["timing"], "in-process")

    def test_the_page_has_every_scene_and_its_numbers(self):
        parsed = page.parse(self.html)
        scenes_in_page = {c.get("data-scene") for c in parsed.cells if "data-scene" in c}
        self.assertEqual(scenes_in_page, {s["id"] for s in self.results["scenes"]})
        for c in parsed.cells:
            if "data-run" in c:
                run = [r for s in self.results["scenes"] if s["id"] == c["data-scene"] for r in s["runs"]
                       if r["id"] == c["data-run"]][0]
                want = run[c["data-key"]]
                self.assertEqual(None if c["data-value"] == "null" else float(c["data-value"]), want, c)

    def test_scaling_has_every_filter(self):
        fits = {f["filter"] for f in self.results["scaling"]["fits"]}
        self.assertEqual(fits, set(self.filters))


if __name__ == "__main__":
    unittest.main()
