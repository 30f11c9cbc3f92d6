"""`mcrecon report` end to end (issue 20): sample scenes of every kind (still, sequence, light
field) plus a user's render with a --peer and the built-in OpenCV peer, timed the same way; the
page's numbers equal results.json's, results.csv's equal them too, the noisy rows equal
`mcrecon compare`, each error map's mean is its run's relMSE, the page loads in headless
Chromium with every image; nothing of the inputs is touched and nothing half-written is left;
mcrecon.report() from Python gives the CLI's numbers; bad options and a failing peer are named."""
import csv
import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402
import OpenImageIO as oiio  # noqa: E402
import test_report_page as page  # noqa: E402  (its HTML parser and Chromium helpers)

DATA = os.path.join(tu.source_dir(), "samples", "data")
WALL4 = os.path.join(DATA, "wall", "wall_4spp.exr")
WALL_REF = os.path.join(DATA, "wall", "wall_ref.exr")
FILTERS = ["box", "bmfr", "sheared", "auto"]
BLUR = "blur=oiiotool {colour.exr} --blur 3x3 -o {output.exr}"


def sha(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def read(path):
    inp = oiio.ImageInput.open(path)
    assert inp is not None, oiio.geterror()
    try:
        return inp.read_image(oiio.FLOAT), inp.spec()
    finally:
        inp.close()


class ReportTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="mcrecon_report_")
        cls.out = os.path.join(cls.tmp, "out")
        cls.inputs = [WALL4, WALL_REF, os.path.join(DATA, "wall", "wall_16spp.exr")]
        cls.hashes = {p: sha(p) for p in cls.inputs}
        # Sequences: test_a_user_sequence_with_a_peer and py_test_report_samples (a 16-frame sample
        # sequence here would take this test past 10 minutes under ASan).
        cls.proc = tu.run_cli("report", "-o", cls.out, "--scenes", "wall", "dof_spheres_lf",
                              "--filters", *FILTERS, "--input", WALL4, "--reference", WALL_REF, "--name", "mine",
                              "--input-spp", "4", "--with-samples", "--peer", BLUR, "--scaling-min", "64",
                              "--scaling-max", "128", "-j", "2", timeout=1200)
        with open(os.path.join(cls.out, "results.json")) as f:
            cls.results = json.load(f)
        cls.scenes = {s["id"]: s for s in cls.results["scenes"]}
        with open(os.path.join(cls.out, "report.html")) as f:
            cls.html = f.read()

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_every_filter_auto_and_the_peers_appear_where_they_apply(self):
        self.assertEqual(sorted(self.scenes), ["dof_spheres_lf_16spp", "mine", "wall_16spp"])
        applies = {"mine": {"box", "bmfr", "auto"}, "wall_16spp": {"box", "bmfr", "auto"},
                   "dof_spheres_lf_16spp": {"box", "sheared", "auto"}}
        for sid, s in self.scenes.items():
            with self.subTest(scene=sid):
                defaults = {r["filter"] for r in s["runs"] if r["default"] and r["kind"] != "peer"}
                self.assertEqual(defaults, applies[sid])
                self.assertEqual({k["filter"] for k in s["skipped"]}, set(FILTERS) - applies[sid])
                peers = {r["filter"] for r in s["runs"] if r["kind"] == "peer"}
                self.assertEqual(peers, {"blur", "opencv_nlm"})
                for r in s["runs"]:
                    self.assertNotIn("error", r, r)
                    self.assertIsNotNone(r["relmse"], r["id"])
                auto = [r for r in s["runs"] if r["filter"] == "auto"][0]
                self.assertTrue(auto["chosen"], auto)  # what it picked (or "input"), from its notes
                # A sweep of box's radius besides its defaults.
                self.assertGreaterEqual(len([r for r in s["runs"] if r["filter"] == "box" and r["sweep"]]), 3)

    def test_filters_and_peers_are_timed_the_same_way(self):
        for sid, s in self.scenes.items():
            with self.subTest(scene=sid):
                self.assertEqual(s["timing"], "command")  # peers present: every run is a process
                for r in s["runs"]:
                    self.assertGreater(r["seconds"], 0)
                    if r["kind"] != "peer":  # the process's wall time holds the filter's own time
                        self.assertGreater(r["filter_seconds"], 0)
                        self.assertGreaterEqual(r["seconds"], r["filter_seconds"])
        self.assertIn("spawn to exit", self.results["timing_note"])

    def cells(self):
        return page.parse(self.html).cells

    def test_page_numbers_equal_the_json(self):
        checked = 0
        for cell in self.cells():
            if "data-run" not in cell:
                continue
            run = [r for r in self.scenes[cell["data-scene"]]["runs"] if r["id"] == cell["data-run"]]
            self.assertEqual(len(run), 1, cell)
            want = run[0][cell["data-key"]]
            got = None if cell["data-value"] == "null" else float(cell["data-value"])
            self.assertEqual(got, want, cell)
            checked += 1
        runs = sum(len(s["runs"]) for s in self.scenes.values())
        self.assertGreaterEqual(checked, 2 * runs)  # at least seconds and relMSE of every run
        # The peer sits in the user's render's table and plot.
        self.assertTrue(any(c.get("data-run") == "peer_blur" and c.get("data-scene") == "mine" for c in self.cells()))

    def test_csv_equals_the_json(self):
        with open(os.path.join(self.out, "results.csv")) as f:
            rows = list(csv.DictReader(f))
        runs = [r for r in rows if r["section"] == "run"]
        self.assertEqual(len(runs), sum(len(s["runs"]) for s in self.scenes.values()))
        for row in runs:
            s = [s for s in self.scenes.values() if s["scene"] == row["scene"] and s["input"] == row["input"]][0]
            match = [r for r in s["runs"] if r["filter"] == row["filter"] and r["parameters"] == row["parameters"]]
            self.assertEqual(len(match), 1, row)
            for key in ("seconds", "relmse", "psnr", "ssim"):
                self.assertEqual(float(row[key]), match[0][key], (row, key))
        scaling = [r for r in rows if r["section"] == "scaling"]
        self.assertEqual(len(scaling), len(self.results["scaling"]["rows"]))

    def test_noisy_rows_equal_compare(self):
        for sid, noisy, ref in (("mine", WALL4, WALL_REF), ("wall_16spp", os.path.join(DATA, "wall", "wall_16spp.exr"), WALL_REF)):
            level = [l for l in self.scenes[sid]["levels"] if l["is_input"]][0]
            got = tu.run_cli_json("compare", "--json", ref, noisy)
            for key in ("relmse", "psnr", "ssim"):
                self.assertAlmostEqual(level[key], got[key], delta=1e-12 * max(1.0, abs(got[key])), msg=(sid, key))
        # "worth N x samples" of the input itself is 1 (its own level).
        wall = self.scenes["wall_16spp"]
        self.assertEqual([l["spp"] for l in wall["levels"]], [1, 4, 16, 64])

    def test_error_maps_and_crops(self):
        for sid in ("mine", "wall_16spp", "dof_spheres_lf_16spp"):
            s = self.scenes[sid]
            self.assertGreaterEqual(len(s["crops"]), 1)
            for r in s["runs"]:
                if not r["images"]:
                    self.assertFalse(r["default"], r["id"])  # only sweep points go without pictures
                    continue
                err, spec = read(os.path.join(self.out, r["images"]["error"]))
                self.assertEqual((spec.width, spec.height, spec.nchannels), (s["width"], s["height"], 1))
                self.assertAlmostEqual(float(np.mean(err.astype(np.float64))), r["relmse"], delta=1e-5 * r["relmse"],
                                       msg=(sid, r["id"]))
                for k, crop in enumerate(s["crops"]):
                    one, spec1 = read(os.path.join(self.out, r["images"]["crops_1x"][k]))
                    four, spec4 = read(os.path.join(self.out, r["images"]["crops_4x"][k]))
                    self.assertEqual((spec1.width, spec1.height), (crop["w"], crop["h"]))
                    self.assertEqual((spec4.width, spec4.height), (4 * crop["zoom"]["w"], 4 * crop["zoom"]["h"]))
                    # 4:1 is nearest-neighbour: every 4x4 block one colour.
                    self.assertEqual(float(np.ptp(four.reshape(crop["zoom"]["h"], 4, crop["zoom"]["w"], 4, 3), axis=(1, 3)).max()), 0.0)

    def test_scaling_section(self):
        sc = self.results["scaling"]
        self.assertEqual(sc["sizes"], [64, 128])
        got = {(r["filter"], r["width"]) for r in sc["rows"]}
        for f in FILTERS:
            self.assertIn((f, 64), got)
            self.assertIn((f, 128), got)
        self.assertEqual({f["filter"] for f in sc["fits"]}, set(FILTERS))
        self.assertEqual([f["input"] for f in sc["fits"] if f["filter"] == "sheared"], ["lightfield"])

    def test_page_loads_in_headless_chromium(self):
        exe = page.chromium()
        home = os.path.join(self.tmp, "chromium-home")
        os.makedirs(home, exist_ok=True)
        proc = subprocess.run([exe, "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
                               "--user-data-dir=" + os.path.join(home, "profile"), "--virtual-time-budget=10000",
                               "--dump-dom", "file://" + os.path.abspath(os.path.join(self.out, "report.html"))],
                              capture_output=True, text=True, timeout=120, env=page.clean_env(home))
        self.assertEqual(proc.returncode, 0, proc.stderr[-3000:])
        st = page.parse(proc.stdout).status
        self.assertIsNotNone(st, proc.stdout[:2000])
        self.assertEqual((st.get("data-errors"), st.get("data-broken")), ("0", "0"), st)
        self.assertEqual(int(st.get("data-images")), len(page.parse(self.html).imgs))

    def test_nothing_lost(self):
        for p, h in self.hashes.items():
            self.assertEqual(sha(p), h, p)
        left = [n for n in os.listdir(self.out) if n.startswith(".") and n != ".mcrecon-report.lock"]
        self.assertEqual(left, [])  # no work folder, no temp file
        for root, _, files in os.walk(self.out):
            for n in files:
                if n != ".mcrecon-report.lock":
                    self.assertFalse(n.startswith("."), os.path.join(root, n))  # temp files start with '.'

    def test_python_module_gives_the_cli_numbers(self):
        sys.path.insert(0, os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(tu.source_dir(), "build", "python"))
        import mcrecon
        out = os.path.join(self.tmp, "py")
        lines = []
        r = mcrecon.report(out, scenes=["wall"], filters=["box"], sweeps=False, scaling_max=0, builtin_peers=False,
                           page=False, timing="in-process", progress=lines.append)
        self.assertEqual((r["scenes"], r["runs"], r["failed_runs"]), (1, 1, 0))
        self.assertTrue(any("wall_16spp" in l for l in lines))
        with open(r["results_json"]) as f:
            mine = json.load(f)["scenes"][0]
        cli = [x for x in self.scenes["wall_16spp"]["runs"] if x["id"] == "box"][0]
        box = [x for x in mine["runs"] if x["id"] == "box"][0]
        for key in ("relmse", "psnr", "ssim"):
            self.assertAlmostEqual(box[key], cli[key], delta=1e-9 * abs(cli[key]), msg=key)
        self.assertEqual(mine["timing"], "in-process")


class ReportBadInputTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_report_bad_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def run_bad(self, *args, code=2):
        proc = tu.run_cli("report", "-o", os.path.join(self.tmp, "o"), *args, check=False)
        self.assertEqual(proc.returncode, code, proc.stderr)
        return proc.stderr

    def test_options_are_named(self):
        self.assertIn("--input and --reference come in pairs", self.run_bad("--input", WALL4))
        self.assertIn("needs {output}", self.run_bad("--peer", "x=cat {colour}"))
        self.assertIn("nope", self.run_bad("--filters", "nope"))
        self.assertIn("no sample scene 'nope'", self.run_bad("--scenes", "nope"))
        self.assertIn("missing.exr", self.run_bad("--input", os.path.join(self.tmp, "missing.exr"), "--reference", WALL_REF))
        text = os.path.join(self.tmp, "notes.exr")
        with open(text, "w") as f:
            f.write("not an image\n")
        self.assertIn("notes.exr", self.run_bad("--input", WALL4, "--reference", text))  # found before any work
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "o", "results.json")))

    def test_a_failing_peer_is_reported_not_fatal(self):
        err = self.run_bad("--scenes", "wall", "--filters", "box", "--no-sweeps", "--scaling-max", "0", "--no-page",
                           "--no-builtin-peers", "--peer", "bad=sh -c 'echo peer-broke; exit 3' {output}", code=1)
        self.assertIn("1 failed", err)
        with open(os.path.join(self.tmp, "o", "results.json")) as f:
            runs = json.load(f)["scenes"][0]["runs"]
        bad = [r for r in runs if r["id"] == "peer_bad"][0]
        self.assertIn("exit 3", bad["error"])
        self.assertIn("peer-broke", bad["error"])
        self.assertIsNone(bad["relmse"])

    def test_a_user_sequence_with_a_peer(self):
        anim = os.path.join(DATA, "anim")
        tu.run_cli("report", "-o", os.path.join(self.tmp, "o"), "--input", os.path.join(anim, "anim_1spp_####.exr"),
                   "--reference", os.path.join(anim, "anim_ref_####.exr"), "--frames", "2-5", "--name", "shot",
                   "--filters", "box", "bmfr", "--no-sweeps", "--scaling-max", "0", "--no-builtin-peers", "--no-page",
                   "--peer", BLUR)
        with open(os.path.join(self.tmp, "o", "results.json")) as f:
            s = json.load(f)["scenes"][0]
        self.assertEqual((s["id"], s["kind"], s["frames"], s["timing"]), ("shot", "sequence", 4, "command"))
        self.assertEqual(sorted(r["id"] for r in s["runs"]), ["bmfr", "box", "peer_blur"])
        for r in s["runs"]:
            pf = r["per_frame"]
            self.assertEqual(pf["frame"], [2, 3, 4, 5])
            self.assertIsNone(pf["temporal_error"][0])
            self.assertAlmostEqual(sum(pf["temporal_error"][1:]) / 3, r["temporal_error"], delta=1e-12)
            self.assertAlmostEqual(sum(pf["relmse"]) / 4, r["relmse"], delta=1e-12)
        # the sequence's input level against `mcrecon compare` per frame
        got = tu.run_cli_json("compare", "--json", os.path.join(anim, "anim_ref_####.exr"),
                              os.path.join(anim, "anim_1spp_####.exr"), "--frames", "2-5")
        level = s["levels"][0]
        self.assertIsNone(level["spp"])
        self.assertAlmostEqual(level["relmse"], got["relmse"], delta=1e-12)
        self.assertAlmostEqual(level["temporal_error"], got["temporal_error"], delta=1e-12)

    def test_two_runs_never_share_a_folder(self):
        out = os.path.join(self.tmp, "o")
        os.makedirs(out)
        with open(os.path.join(out, ".mcrecon-report.lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            self.assertIn("another mcrecon report is writing there",
                          self.run_bad("--scenes", "wall", "--filters", "box", "--scaling-max", "0"))


if __name__ == "__main__":
    unittest.main()
