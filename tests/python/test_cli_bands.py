"""A frame in bands of rows (issue 19: bounded memory on huge frames): `--band-rows` and
`--max-memory` give the whole-frame run's pixels bit for bit, with the same header, and are
refused with a message naming the option where bands cannot serve. Oracle: the same filter
run on the whole frame."""
import os
import shutil
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

import mcrecon_testutil as tu

ROOM = os.path.join(tu.source_dir(), "samples", "data", "room", "room_16spp.exr")
ANIM = os.path.join(tu.source_dir(), "samples", "data", "anim", "anim_1spp_####.exr")
PRODUCT = os.path.join(tu.source_dir(), "samples", "data", "product", "product_16spp.exr")


def image(path):
    buf = oiio.ImageBuf(path)
    return buf.get_pixels(oiio.FLOAT), buf.spec()


class BandsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_bands_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def out(self, name):
        return os.path.join(self.tmp, name)

    def test_bands_give_the_whole_frames_pixels(self):
        for f in ("box", "bilateral", "guided", "pwaf"):
            whole, banded = self.out(f + "_whole.exr"), self.out(f + "_bands.exr")
            tu.run_cli("denoise", ROOM, "-o", whole, "-f", f)
            proc = tu.run_cli("denoise", ROOM, "-o", banded, "-f", f, "--band-rows", "64", "-v")
            self.assertIn("3 bands of 64 rows", proc.stderr)
            a, sa = image(whole)
            b, sb = image(banded)
            self.assertEqual(sa.channelnames, sb.channelnames, f)
            np.testing.assert_array_equal(a, b, err_msg=f)
            for key in ("mcreconFilter", "mcreconParameters"):
                self.assertEqual(sa.getattribute(key), sb.getattribute(key), f)
            self.assertFalse([n for n in os.listdir(self.tmp) if n.startswith(".")], "no temp file left")

    def test_a_transparent_renders_alpha_is_filtered_in_bands_of_its_own(self):
        # alpha=filter: after the colour's bands, the alpha's run over the same bands; the whole
        # frame's alpha bit for bit, and not the input's. box reads no normal, but the alpha's
        # partly covered pixels are read from it (the bands once read none: 356 pixels differed).
        for f in ("box", "bilateral", "pwaf"):
            whole, banded = self.out(f + "_whole.exr"), self.out(f + "_bands.exr")
            tu.run_cli("denoise", PRODUCT, "-o", whole, "-f", f)
            proc = tu.run_cli("denoise", PRODUCT, "-o", banded, "-f", f, "--band-rows", "64", "-v")
            self.assertIn("alpha: filtered by " + f, proc.stderr)
            self.assertIn("alpha: 3 bands of 64 rows", proc.stderr)
            a, sa = image(whole)
            b, _ = image(banded)
            np.testing.assert_array_equal(a, b, err_msg=f)
            given, sg = image(PRODUCT)
            self.assertFalse(np.array_equal(b[:, :, 3], given[:, :, list(sg.channelnames).index("ViewLayer.Combined.A")]))

    def test_max_memory_chooses_bands_and_says_when_too_little(self):
        done = tu.run_cli("denoise", ROOM, "-o", self.out("m.exr"), "-f", "atrous", "--max-memory", "400", "-v")
        self.assertRegex(done.stderr, r"\d+ bands? of \d+ rows")
        tiny = tu.run_cli("denoise", ROOM, "-o", self.out("t.exr"), "-f", "atrous", "--max-memory", "100", check=False)
        self.assertEqual(tiny.returncode, 2)
        self.assertIn("--max-memory 100 MB is too little", tiny.stderr)
        self.assertFalse(os.path.exists(self.out("t.exr")))

    def test_what_bands_cannot_do_is_refused(self):
        cases = [
            (["-f", "bmfr"], "--band-rows: a temporal run"),
            (["-f", "box", "--region", "0,0,10,10"], "--band-rows: --region"),
            (["-f", "box", "--keep-passes"], "--band-rows: --keep-passes"),
            (["-f", "gaussian", "--set", "foveated=true"], "foveated=true"),
        ]
        for extra, message in cases:
            proc = tu.run_cli("denoise", ROOM, "-o", self.out("r.exr"), "--band-rows", "64", *extra, check=False)
            self.assertEqual(proc.returncode, 2, extra)
            self.assertIn(message, proc.stderr, extra)
            self.assertFalse(os.path.exists(self.out("r.exr")), extra)
        temporal = tu.run_cli("denoise", ANIM, "--frames", "1-2", "-o", self.out("s_####.exr"), "-f", "box",
                              "--accumulate", "--max-memory", "500", check=False)
        self.assertEqual(temporal.returncode, 2)
        self.assertIn("--max-memory: a temporal run", temporal.stderr)
        self.assertFalse(os.path.exists(self.out("s_0001.exr")))

    def test_a_sequence_runs_frame_by_frame_in_bands(self):
        tu.run_cli("denoise", ANIM, "--frames", "1-3", "-o", self.out("w_####.exr"), "-f", "pwaf")
        tu.run_cli("denoise", ANIM, "--frames", "1-3", "-o", self.out("b_####.exr"), "-f", "pwaf", "--band-rows", "64")
        for f in (1, 2, 3):
            np.testing.assert_array_equal(image(self.out("w_%04d.exr" % f))[0], image(self.out("b_%04d.exr" % f))[0])
        again = tu.run_cli("denoise", ANIM, "--frames", "1-3", "-o", self.out("b_####.exr"), "-f", "pwaf",
                           "--band-rows", "64", "--resume")
        self.assertIn("3 of 3 frames already done", again.stderr)


if __name__ == "__main__":
    unittest.main()
