"""The page of `mcrecon report` (report/render_report.py) and the OpenCV peer (report/peers/opencv_nlm.py).

No mcrecon build needed: a synthetic report folder (results.json after the schema in report/README.md,
tiny PNGs and EXR error maps) is rendered, then checked three ways: every numeric cell's `data-value`
equals the JSON value exactly; every plot is written and embedded; headless Chromium loads the page
with no script error and every image decoded, and a screenshot of it is not blank.
The peer: Gaussian noise of known sigma on a smooth gradient (EXR and PFM) comes out with at least
3x less MSE against the clean gradient; missing or non-image input exits 2 naming the file.
Needs python3-matplotlib, python3-opencv and chromium (`bash setup.sh` installs them): missing, the
tests fail, they do not skip. Environment (ctest): MCRECON_SOURCE_DIR.
"""
import base64
import html.parser
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

SRC = os.environ.get("MCRECON_SOURCE_DIR") or os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))
REPORT_DIR = os.path.join(SRC, "report")
PEER = os.path.join(REPORT_DIR, "peers", "opencv_nlm.py")
PYTHON = "/usr/bin/python3"
INSTALL_HINT = "`bash setup.sh` installs python3-matplotlib, python3-opencv and chromium"
# The sanitizer CI stage sets these for every test: not for a browser or a plain Python peer.
SANITIZER_ENV = ("LD_PRELOAD", "ASAN_OPTIONS", "UBSAN_OPTIONS", "LSAN_OPTIONS", "MSAN_OPTIONS", "TSAN_OPTIONS")


def clean_env(home=None):
    env = {k: v for k, v in os.environ.items() if k not in SANITIZER_ENV}
    if home:
        env["HOME"] = home
    return env


def renderer():
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise AssertionError("matplotlib is missing: " + INSTALL_HINT)
    if REPORT_DIR not in sys.path:
        sys.path.insert(0, REPORT_DIR)
    import render_report
    return render_report


def chromium():
    for name in ("chromium", "chromium-browser"):
        p = shutil.which(name)
        if p:
            return p
    if os.path.exists("/usr/bin/chromium"):
        return "/usr/bin/chromium"
    raise AssertionError("chromium is missing: " + INSTALL_HINT)


# ---------------------------------------------------------------- the synthetic report folder

def write_image(path, px, fmt=oiio.UINT8):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    px = np.ascontiguousarray(px, dtype=np.float32)
    if px.ndim == 2:
        px = px[:, :, None]
    if path.endswith(".pfm"):  # Debian's OpenImageIO 2.4 reads PFM but has no writer
        with open(path, "wb") as f:
            f.write(b"PF\n%d %d\n-1.0\n" % (px.shape[1], px.shape[0]))
            f.write(np.ascontiguousarray(px[::-1], dtype="<f4").tobytes())
        return
    spec = oiio.ImageSpec(px.shape[1], px.shape[0], px.shape[2], fmt)
    if px.shape[2] == 1:
        spec.channelnames = ("Y",)
    out = oiio.ImageOutput.create(path)
    assert out is not None, oiio.geterror()
    assert out.open(path, spec), out.geterror()
    assert out.write_image(px), out.geterror()
    out.close()


def gradient(w, h, seed):
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    rng = np.random.default_rng(seed)
    base = np.stack([x / w, y / h, 0.5 + 0.5 * np.sin((x + y) / 9.0 + seed)], axis=2)
    return np.clip(base + 0.05 * rng.standard_normal(base.shape), 0, 1)


def make_run(rid, filt, kind, seconds, relmse, images, sweep=None, default=True, frames=1, **extra):
    run = {"id": rid, "filter": filt, "kind": kind, "parameters": "" if default else extra.pop("parameters", ""),
           "default": default, "sweep": sweep, "seconds": seconds,
           "filter_seconds": None if kind == "peer" else seconds * 0.8,
           "peak_memory_mb": None if kind == "peer" else 30.5 + seconds,
           "relmse": relmse, "psnr": 30.0 - 10 * np.log10(relmse), "ssim": 1.0 - relmse,
           "temporal_error": 0.01 + relmse / 7 if frames > 1 else None,
           "worth_x_samples": 1.0 / relmse / 3.0, "pareto_relmse": False, "pareto_ssim": False,
           "chosen": None, "notes": [], "per_frame": None, "images": images}
    if frames > 1:
        run["per_frame"] = {"frame": list(range(1, frames + 1)),
                            "relmse": [relmse * (1 + 0.1 * i) for i in range(frames)],
                            "temporal_error": [None] + [0.01 * i + relmse / 5 for i in range(1, frames)]}
    run.update(extra)
    return run


def build_scene(out, sid, kind, frames, split, timing, seed):
    w, h = 96, 80
    d = "images/" + sid
    write_image(os.path.join(out, d, "noisy.png"), gradient(w, h, seed))
    write_image(os.path.join(out, d, "reference.png"), gradient(w, h, seed) * 0.9)
    crop = {"x": 8, "y": 6, "w": 64, "h": 64, "zoom": {"x": 30, "y": 30, "w": 16, "h": 16}}
    for name in ("noisy", "reference"):
        crop[name + "_1x"] = "%s/%s_crop0_1x.png" % (d, name)
        crop[name + "_4x"] = "%s/%s_crop0_4x.png" % (d, name)
        write_image(os.path.join(out, crop[name + "_1x"]), gradient(64, 64, seed + 1))
        write_image(os.path.join(out, crop[name + "_4x"]), np.repeat(np.repeat(gradient(16, 16, seed + 2), 4, 0), 4, 1))
    rng = np.random.default_rng(seed)

    def imgs(rid):
        im = {"full": "%s/%s.png" % (d, rid), "error": "errors/%s/%s.exr" % (sid, rid),
              "crops_1x": ["%s/%s_crop0_1x.png" % (d, rid)], "crops_4x": ["%s/%s_crop0_4x.png" % (d, rid)]}
        write_image(os.path.join(out, im["full"]), gradient(w, h, seed + 3))
        write_image(os.path.join(out, im["crops_1x"][0]), gradient(64, 64, seed + 4))
        write_image(os.path.join(out, im["crops_4x"][0]), np.repeat(np.repeat(gradient(16, 16, 5), 4, 0), 4, 1))
        err = rng.lognormal(-4.0, 1.5, (h, w)).astype(np.float32)
        err[:3, :3] = 0.0  # zeros must be clipped, not break the log scale
        write_image(os.path.join(out, im["error"]), err, oiio.FLOAT)
        return im

    runs = [
        make_run("box", "box", "filter", 0.0123, 0.30000000000000004, imgs("box"), frames=frames,
                 pareto_relmse=True, pareto_ssim=True),
        make_run("bilateral", "bilateral", "filter", 0.05, 0.1, imgs("bilateral"), frames=frames,
                 pareto_relmse=True, notes=["a note <with> markup & ampersand"]),
        make_run("bilateral@spatial_sigma=1", "bilateral", "filter", 0.03, 0.2, None, default=False,
                 parameters="spatial_sigma=1", sweep={"param": "spatial_sigma", "value": 1.0}, frames=frames),
        make_run("bilateral@spatial_sigma=4", "bilateral", "filter", 0.08, 0.09, None, default=False,
                 parameters="spatial_sigma=4", sweep={"param": "spatial_sigma", "value": 4.0}, frames=frames,
                 psnr=None, worth_x_samples=None, pareto_relmse=True),
        make_run("auto", "auto", "auto", 0.2, 0.07, imgs("auto"), frames=frames, chosen="bilateral",
                 pareto_relmse=True, pareto_ssim=True),
        make_run("opencv_nlm", "opencv_nlm", "peer", 1.7, 0.12345678901234567, imgs("opencv_nlm"), frames=frames),
    ]
    levels = []
    for spp, rel in ((16, 0.87), (64, 0.25), (256, 0.066)):
        lv = {"label": "noisy 16 spp (input)" if spp == 16 else "%d spp (%dx)" % (spp, spp // 16), "spp": spp,
              "is_input": spp == 16, "relmse": rel, "psnr": 20.0 + spp / 100.0, "ssim": 0.4 + spp / 1000.0,
              "temporal_error": 0.3 / spp if frames > 1 else None, "per_frame": None}
        if frames > 1:
            lv["per_frame"] = {"frame": list(range(1, frames + 1)), "relmse": [rel] * frames,
                               "temporal_error": [None] + [0.3 / spp] * (frames - 1)}
        levels.append(lv)
    return {"id": sid, "scene": sid.split("_")[0], "input": "16spp", "spp": 16, "kind": kind, "split": split,
            "width": w, "height": h, "frames": frames, "reference_spp": 2048, "timing": timing,
            "images": {"noisy": d + "/noisy.png", "reference": d + "/reference.png"},
            "crops": [crop], "levels": levels, "runs": runs}


def build_report(out):
    scenes = [build_scene(out, "room_16spp", "still", 1, "tune", "command", 1),
              build_scene(out, "corridor_16spp", "sequence", 3, "report", "in-process", 2)]
    rows, fits = [], []
    for filt, inp, k in (("box", "flat", 0.15), ("bilateral", "flat", 0.6), ("deep_box", "deep", 1.1)):
        for size in (256, 512, 1024):
            px = size * size
            rows.append({"filter": filt, "input": inp, "width": size, "height": size, "pixels": px,
                         "seconds": k * px / 1e6, "peak_memory_mb": 12.0 + 40.0 * px / 1e6})
        fits.append({"filter": filt, "input": inp, "slope": 1.0 + k / 100, "seconds_per_megapixel": k,
                     "peak_memory_mb_per_megapixel": 40.1})
    res = {"format": "mcrecon-report-1", "created": "2026-12-04T23:50:00Z", "mcrecon": "mcrecon 0.0 (test)",
           "machine": {"cpu": "Test CPU", "logical_cores": 2, "threads": 2, "os": "Linux", "memory_gb": 23.4},
           "timing_note": "wall clock", "memory_note": "peak RSS", "scenes": scenes,
           "scaling": {"method": "synthetic", "threads": 2, "sizes": [256, 512, 1024], "rows": rows, "fits": fits}}
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump(res, f, indent=1)
    return res


class PageParser(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.cells, self.imgs, self.links, self.status = [], [], [], None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "data-value" in a:
            self.cells.append(a)
        if tag == "img":
            self.imgs.append(a.get("src") or "")
        for k in ("src", "href"):
            if k in a and tag != "img":
                self.links.append(a[k])
        if tag == "link":
            self.links.append(a.get("href") or "")
        if a.get("id") == "report-status":
            self.status = a


def parse(text):
    p = PageParser()
    p.feed(text)
    return p


class ReportPageTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="mcrecon_report_page_")
        cls.out = os.path.join(cls.tmp, "report")
        os.makedirs(cls.out)
        cls.res = build_report(cls.out)
        cls.page = renderer().render(cls.out)
        with open(cls.page, encoding="utf-8") as f:
            cls.text = f.read()
        cls.parsed = parse(cls.text)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_cells_equal_json_exactly(self):
        scenes = {s["id"]: s for s in self.res["scenes"]}
        seen = set()
        for a in self.parsed.cells:
            key = a["data-key"]
            if "data-fit" in a:
                obj, where = self.res["scaling"]["fits"][int(a["data-fit"])], ("fit", a["data-fit"])
            elif "data-level" in a:
                obj = scenes[a["data-scene"]]["levels"][int(a["data-level"])]
                where = (a["data-scene"], "level", a["data-level"])
            else:
                obj = {r["id"]: r for r in scenes[a["data-scene"]]["runs"]}[a["data-run"]]
                where = (a["data-scene"], a["data-run"])
            self.assertIn(key, obj, where)
            self.assertEqual(json.loads(a["data-value"]), obj[key], (where, key))
            self.assertEqual(a["data-value"], json.dumps(obj[key]), (where, key))
            seen.add(where + (key,))
        # Every run's numbers are on the page, once each (temporal error only for sequences).
        keys = ["seconds", "filter_seconds", "peak_memory_mb", "relmse", "psnr", "ssim", "worth_x_samples"]
        for s in self.res["scenes"]:
            for r in s["runs"]:
                for k in keys + (["temporal_error"] if s["frames"] > 1 else []):
                    self.assertIn((s["id"], r["id"], k), seen)
        self.assertEqual(len(seen), len(self.parsed.cells), "a cell appears twice")
        # Null cells show '-', the exact float repr survives.
        self.assertIn('data-value="0.30000000000000004"', self.text)
        self.assertIn('data-key="psnr" data-value="null">-</td>', self.text)
        self.assertIn(">3.333x</td>", self.text)  # bilateral's worth_x_samples, 1 / 0.1 / 3
        self.assertNotIn("<with>", self.text)  # notes escaped

    def test_plots_written_and_embedded(self):
        plots = os.path.join(self.out, "plots")
        names = sorted(os.listdir(plots))
        expected = []
        for s in self.res["scenes"]:
            expected += ["%s_pareto_relmse.png" % s["id"], "%s_pareto_ssim.png" % s["id"],
                         "%s_errors.png" % s["id"], "%s_crops.png" % s["id"]]
            if s["frames"] > 1:
                expected += ["%s_frames_relmse.png" % s["id"], "%s_frames_temporal_error.png" % s["id"]]
            if s["timing"] == "command":  # the filters' own time too
                expected += ["%s_filter_time_relmse.png" % s["id"]]
        expected += ["scaling_memory.png", "scaling_time.png"]
        self.assertEqual(names, sorted(expected))
        embedded = set(self.parsed.imgs)
        for n in names:
            with open(os.path.join(plots, n), "rb") as f:
                data = f.read()
            self.assertEqual(data[:8], b"\x89PNG\r\n\x1a\n", n)
            self.assertTrue("data:image/png;base64," + base64.b64encode(data).decode() in embedded,
                            "plots/%s is not embedded in the page" % n)
        # Self-contained: every image a PNG data URI that decodes whole (a browser shows a truncated
        # PNG without an error); no file, network or stylesheet link.
        probe = os.path.join(self.tmp, "probe.png")
        for src in embedded:
            self.assertTrue(src.startswith("data:image/png;base64,"), src[:80])
            with open(probe, "wb") as f:
                f.write(base64.b64decode(src.split(",", 1)[1]))
            inp = oiio.ImageInput.open(probe)
            self.assertIsNotNone(inp, oiio.geterror())
            px = inp.read_image(oiio.FLOAT)
            err = inp.geterror()
            inp.close()
            self.assertIsNotNone(px, "an embedded PNG does not decode: %s" % err)
        for link in self.parsed.links:
            self.assertTrue(link.startswith("#"), link)
        self.assertNotIn("http://", self.text.replace("http://www.w3.org", ""))
        self.assertNotIn("https://", self.text)
        self.assertNotIn("missing image", self.text)
        # plots + per crop row (noisy, 4 runs with crops, reference) x 2 scales + full strip (4 + 2)
        per_scene = {s["id"]: 2 * 6 + 6 for s in self.res["scenes"]}
        self.assertGreaterEqual(len(self.parsed.imgs), len(expected) + sum(per_scene.values()))
        # No temp file left behind.
        for d in (self.out, plots):
            self.assertEqual([n for n in os.listdir(d) if ".tmp" in n], [], d)

    def test_headless_chromium_loads_every_image(self):
        exe = chromium()
        home = os.path.join(self.tmp, "chromium-home")
        os.makedirs(home, exist_ok=True)
        url = "file://" + os.path.abspath(self.page)
        base = [exe, "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
                "--user-data-dir=" + os.path.join(home, "profile"), "--virtual-time-budget=10000"]
        proc = subprocess.run(base + ["--dump-dom", url], capture_output=True, text=True, timeout=120,
                              env=clean_env(home))
        self.assertEqual(proc.returncode, 0, proc.stderr[-3000:])
        st = parse(proc.stdout).status
        self.assertIsNotNone(st, "no report-status in the dumped DOM:\n" + proc.stdout[:2000])
        self.assertEqual(st.get("data-errors"), "0", st)
        self.assertEqual(st.get("data-broken"), "0", st)
        self.assertEqual(st.get("data-images"), str(len(self.parsed.imgs)), st)
        shot = os.path.join(self.tmp, "screenshot.png")
        proc = subprocess.run(base + ["--screenshot=" + shot, "--window-size=1400,2400", url],
                              capture_output=True, text=True, timeout=120, env=clean_env(home))
        self.assertEqual(proc.returncode, 0, proc.stderr[-3000:])
        self.assertTrue(os.path.exists(shot), proc.stderr[-3000:])
        inp = oiio.ImageInput.open(shot)
        self.assertIsNotNone(inp, oiio.geterror())
        px = inp.read_image(oiio.FLOAT)
        inp.close()
        self.assertEqual(px.shape[:2], (2400, 1400))
        self.assertGreater(float(np.var(px)), 1e-4, "blank screenshot")

    def test_command_line_and_bad_folder(self):
        out = os.path.join(self.tmp, "cli")
        os.makedirs(out)
        script = os.path.join(REPORT_DIR, "render_report.py")
        proc = subprocess.run([PYTHON, script, out], capture_output=True, text=True, timeout=120, env=clean_env())
        self.assertEqual(proc.returncode, 2)
        self.assertIn(os.path.join(out, "results.json"), proc.stderr)
        with open(os.path.join(out, "results.json"), "w") as f:
            json.dump({"format": "mcrecon-report-1", "scenes": [self.res["scenes"][0]]}, f)
        shutil.copytree(os.path.join(self.out, "images"), os.path.join(out, "images"))
        shutil.copytree(os.path.join(self.out, "errors"), os.path.join(out, "errors"))
        proc = subprocess.run([PYTHON, script, out], capture_output=True, text=True, timeout=300, env=clean_env())
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("page: scene 1/1 room_16spp", proc.stderr)
        self.assertTrue(os.path.exists(os.path.join(out, "report.html")))


# ---------------------------------------------------------------- the OpenCV peer

def read_image(path):
    inp = oiio.ImageInput.open(path)
    assert inp is not None, oiio.geterror()
    px = inp.read_image(oiio.FLOAT)
    inp.close()
    return np.asarray(px, dtype=np.float64)


class OpenCvPeerTest(unittest.TestCase):
    def setUp(self):
        try:
            import cv2  # noqa: F401
        except ImportError:
            raise AssertionError("OpenCV (cv2) is missing: " + INSTALL_HINT)
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_opencv_peer_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def peer(self, *args):
        return subprocess.run([PYTHON, PEER, *map(str, args)], capture_output=True, text=True, timeout=300,
                              env=clean_env())

    def test_reduces_noise_exr_and_pfm(self):
        h, w, sigma = 96, 128, 0.05
        y, x = np.mgrid[0:h, 0:w].astype(np.float64)
        clean = np.stack([0.3 + 0.5 * x / w, 0.3 + 0.5 * y / h, 0.4 + 0.3 * (x + y) / (w + h)], axis=2)
        noisy = clean + np.random.default_rng(7).normal(0.0, sigma, clean.shape)
        noisy[5, 7, 1] = np.nan  # replaced by 0 and counted
        for ext in ("exr", "pfm"):
            src, dst = os.path.join(self.tmp, "in." + ext), os.path.join(self.tmp, "out." + ext)
            write_image(src, noisy, oiio.FLOAT)
            proc = self.peer("--input", src, "--output", dst)
            self.assertEqual(proc.returncode, 0, proc.stderr)
            self.assertIn("1 non-finite", proc.stderr)
            out = read_image(dst)
            self.assertEqual(out.shape, clean.shape)
            self.assertTrue(np.all(np.isfinite(out)))
            mask = np.ones(clean.shape[:2], bool)
            mask[5, 7] = False  # the replaced pixel is not noise
            mse_in = np.mean((noisy - clean)[mask] ** 2)
            mse_out = np.mean((out - clean)[mask] ** 2)
            self.assertLess(mse_out * 3.0, mse_in, (ext, mse_in, mse_out))
            self.assertEqual([n for n in os.listdir(self.tmp) if ".tmp" in n], [])
        # A given h is used as is: h tiny leaves the image nearly as noisy.
        proc = self.peer("--input", src, "--output", dst, "--h", "1")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertGreater(np.mean((read_image(dst) - clean)[mask] ** 2) * 2.0, mse_in)

    def test_bad_input_exits_2_naming_the_file(self):
        missing = os.path.join(self.tmp, "nothing_here.exr")
        text = os.path.join(self.tmp, "not_an_image.exr")
        with open(text, "w") as f:
            f.write("this is not an image\n")
        for path in (missing, text):
            dst = os.path.join(self.tmp, "out.exr")
            proc = self.peer("--input", path, "--output", dst)
            self.assertEqual(proc.returncode, 2, proc.stderr)
            self.assertIn(path, proc.stderr)
            self.assertFalse(os.path.exists(dst))


if __name__ == "__main__":
    unittest.main()
