"""Filter `auto` through the CLI: listed by `filters` (text and --json, with its parameter table)
and `info`, and `denoise -f auto --verbose` names what it chose. The oracle for the choice being
the one that ran: the output equals `denoise -f CHOSEN` of the same file bit for bit, or the input
itself when auto kept it.

Run by ctest as `/usr/bin/python3 tests/python/test_cli_auto.py` with MCRECON_BIN and
MCRECON_SOURCE_DIR.
"""
import os
import re
import shutil
import sys
import tempfile
import unittest

import json

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

RGBA = ["R", "G", "B", "A"]
ROOM = os.path.join(tu.source_dir(), "samples", "data", "room", "room_16spp.exr")
ANIM = os.path.join(tu.source_dir(), "samples", "data", "anim", "anim_1spp_####.exr")


def header(path, name):
    inp = oiio.ImageInput.open(path)
    assert inp, oiio.geterror()
    try:
        return inp.spec().get_string_attribute(name)
    finally:
        inp.close()


def same_bits(a, b):
    a, b = np.ascontiguousarray(a, np.float32), np.ascontiguousarray(b, np.float32)
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def chosen_in(stderr):
    """The filter `--verbose` says auto chose ("input" when it kept the input)."""
    m = re.findall(r"auto: chose (?:the )?(\S+)", stderr)
    assert len(m) == 1, "expected one 'auto: chose ...' note:\n" + stderr
    return m[0]


class AutoCliTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_auto_")
        self.addCleanup(shutil.rmtree, self.tmp, ignore_errors=True)

    def path(self, name):
        return os.path.join(self.tmp, name)

    def colour_only(self, name, rgb):
        h, w = rgb.shape[:2]
        p = self.path(name)
        tu.write_exr(p, np.concatenate([rgb, np.ones((h, w, 1))], axis=-1), RGBA)
        return p

    def test_filters_lists_auto_with_its_parameters(self):
        filters = tu.run_cli_json("filters", "--json")["filters"]
        names = [f["name"] for f in filters]
        self.assertIn("auto", names)
        auto = filters[names.index("auto")]
        self.assertEqual(auto["required_passes"], ["colour"])
        self.assertFalse(auto["temporal"])
        params = {p["name"]: p for p in auto["parameters"]}
        self.assertEqual(set(params), {"sample_fraction", "converged", "min_gain", "kept_firefly_k", "pairs", "exposure", "components", "alpha"})
        self.assertEqual(params.pop("components")["choices"], ["beauty", "light_passes"])  # every filter's
        self.assertEqual(params.pop("exposure")["choices"], ["auto", "off"])  # every image filter's
        self.assertEqual(params.pop("alpha")["choices"], ["filter", "keep"])  # every flat-frame filter's
        pairs = params.pop("pairs")
        self.assertEqual((pairs["type"], pairs["default"]), ("bool", True))
        for p in params.values():
            self.assertEqual(p["type"], "float")
            self.assertLessEqual(p["min"], p["default"])
            self.assertLessEqual(p["default"], p["max"])
        text = tu.run_cli("filters").stdout
        self.assertRegex(text, r"(?m)^auto: ")
        self.assertIn("--set sample_fraction", text)

    def test_info_says_auto_can_run_on_colour_alone(self):
        rng = np.random.default_rng(1)
        only = self.colour_only("only.exr", rng.random((12, 16, 3)))
        for path, uses in ((only, []), (ROOM, None)):
            entry = {f["name"]: f for f in tu.run_cli_json("info", "--json", path)["filters"]}["auto"]
            self.assertTrue(entry["can_run"], entry)
            self.assertEqual(entry["missing"], [])
            if uses is not None:
                self.assertEqual(entry["uses"], uses)
        self.assertIn("auto: can run", tu.run_cli("info", only).stdout)

    def test_denoise_auto_runs_the_filter_it_names(self):
        out = self.path("auto.exr")
        err = tu.run_cli("denoise", ROOM, "-o", out, "-f", "auto", "--verbose").stderr
        chosen = chosen_in(err)
        self.assertIn("auto: estimated relMSE", err)
        names = [f["name"] for f in tu.run_cli_json("filters", "--json")["filters"]]
        self.assertIn(chosen, [n for n in names if n != "auto"] + ["input"])
        # On this 16 spp render some filter is estimated to help (the sample's reference says so too).
        self.assertNotEqual(chosen, "input", err)
        want = self.path("chosen.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", chosen)
        self.assertTrue(same_bits(tu.read_channels(out, RGBA), tu.read_channels(want, RGBA)),
                        "auto's output is not `denoise -f %s` of the same file" % chosen)

    def test_json_lines_and_the_header_say_what_auto_ran(self):
        out = self.path("auto.exr")
        r = tu.run_cli("denoise", ROOM, "-o", out, "-f", "auto", "--json", "-v")
        lines = r.stdout.splitlines()
        self.assertEqual(len(lines), 1, r.stdout)
        rec = json.loads(lines[0])
        chosen = chosen_in(r.stderr)  # the note --verbose prints
        self.assertEqual(rec["chosen"], {"beauty": chosen})
        self.assertEqual((rec["input"], rec["output"], rec["filter"]), (ROOM, out, "auto"))
        self.assertIn("auto: chose " + chosen + " with its defaults", rec["notes"])
        self.assertEqual(set(rec["ms"]), {"read", "filter", "write"})
        self.assertTrue(all(v >= 0 for v in rec["ms"].values()), rec["ms"])
        self.assertEqual(header(out, "mcreconChosen"), chosen)
        self.assertIn("auto: chose " + chosen, header(out, "mcreconNotes"))
        # The record's choice is the filter that ran: its output bit for bit.
        want = self.path("chosen.exr")
        tu.run_cli("denoise", ROOM, "-o", want, "-f", rec["chosen"]["beauty"])
        self.assertTrue(same_bits(tu.read_channels(out, RGBA), tu.read_channels(want, RGBA)))
        # Another filter: no choice, in the record or the header; a sequence: a line per frame.
        seq = self.path("box_####.exr")
        r = tu.run_cli("denoise", ANIM, "--frames", "1-2", "-o", seq, "-f", "box", "--json")
        recs = [json.loads(l) for l in r.stdout.splitlines()]
        self.assertEqual([(x["input"][-8:], x["output"][-8:], x["chosen"]) for x in recs],
                         [("0001.exr", "0001.exr", None), ("0002.exr", "0002.exr", None)])
        self.assertEqual(header(self.path("box_0001.exr"), "mcreconChosen"), "")

    def test_denoise_auto_on_colour_only_files(self):
        h, w = 64, 80
        y, x = np.mgrid[0:h, 0:w]
        clean = np.stack([0.2 + 0.6 * x / w, 0.3 + 0.4 * y / h, np.full((h, w), 0.5)], axis=-1)
        noise = np.random.default_rng(3).gamma(4.0, 0.25, (h, w, 1))  # mean 1: 1/sqrt(4) relative noise
        # A noisy render: a filter is run and named, and the output is that filter's.
        noisy = self.colour_only("noisy.exr", clean * noise)
        out = self.path("noisy_auto.exr")
        err = tu.run_cli("denoise", noisy, "-o", out, "-f", "auto", "-v").stderr
        chosen = chosen_in(err)
        self.assertNotEqual(chosen, "input", err)
        want = self.path("noisy_chosen.exr")
        tu.run_cli("denoise", noisy, "-o", want, "-f", chosen)
        self.assertTrue(same_bits(tu.read_channels(out, RGBA), tu.read_channels(want, RGBA)))
        # A render without noise: the input is kept as it is, and said so.
        flat = self.colour_only("clean.exr", clean)
        out = self.path("clean_auto.exr")
        err = tu.run_cli("denoise", flat, "-o", out, "-f", "auto", "-v").stderr
        self.assertEqual(chosen_in(err), "input", err)
        self.assertTrue(same_bits(tu.read_channels(out, RGBA), tu.read_channels(flat, RGBA)))


if __name__ == "__main__":
    unittest.main()
