"""Batch runs at farm scale (issue 19): frame lists as oiiotool writes them, --warmup (a chunk
of a temporal run matches the single run), --resume that verifies each output's header and
replays only what the history needs, and `mcrecon plan`, whose commands, run one by one, give
the single run's pixels. Oracles: the single run of the same frames, and the header each
output records (mcreconFilter, mcreconParameters, mcreconInput)."""
import os
import re
import shlex
import shutil
import subprocess
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

import mcrecon_testutil as tu

ANIM = os.path.join(tu.source_dir(), "samples", "data", "anim", "anim_1spp_####.exr")


def pixels(path):
    buf = oiio.ImageBuf(path)
    return buf.get_pixels(oiio.FLOAT)


def written(d):
    return sorted(f for f in os.listdir(d) if not f.startswith("."))


class BatchTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_batch_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def dir(self, name):
        d = os.path.join(self.tmp, name)
        os.makedirs(d, exist_ok=True)
        return d

    def sequence(self, n, w=12, h=10, seed=3):
        d = self.dir("in")
        rng = np.random.default_rng(seed)
        for f in range(1, n + 1):
            tu.write_exr(os.path.join(d, "s_%04d.exr" % f), rng.random((h, w, 4), dtype=np.float32))
        return os.path.join(d, "s_####.exr")

    def bmfr(self, out_dir, frames, *extra, check=True):
        return tu.run_cli("denoise", ANIM, "-o", os.path.join(out_dir, "o_####.exr"), "-f", "bmfr",
                          "--frames", frames, *extra, check=check)

    def test_frame_lists_and_steps(self):
        src = self.sequence(6)
        for text, want in (("1-6x2", [1, 3, 5]), ("1-6y2", [2, 4, 6]), ("2,5", [2, 5]), ("1-2,5-6", [1, 2, 5, 6])):
            out = self.dir("o" + text.replace(",", "_"))
            proc = tu.run_cli("denoise", src, "-o", os.path.join(out, "o_####.exr"), "-f", "box", "--frames", text)
            self.assertEqual(written(out), ["o_%04d.exr" % f for f in want], text)
            self.assertIn("%d written" % len(want), proc.stderr)
            # compare reads the same lists: an image against itself is exact on every frame.
            j = tu.run_cli_json("compare", os.path.join(out, "o_####.exr"), os.path.join(out, "o_####.exr"),
                                "--frames", text, "--json")
            self.assertEqual([x["frame"] for x in j["frames"]], want)
        for bad in ("6-1", "1-6x0", "3,2", "2,2"):
            proc = tu.run_cli("denoise", src, "-o", os.path.join(self.tmp, "b_####.exr"), "-f", "box",
                              "--frames", bad, check=False)
            self.assertEqual(proc.returncode, 2, bad)
            self.assertIn("--frames '%s'" % bad, proc.stderr)

    def test_temporal_filters_need_consecutive_frames(self):
        proc = tu.run_cli("denoise", ANIM, "-o", os.path.join(self.tmp, "x_####.exr"), "-f", "bmfr",
                          "--frames", "1-8x2", check=False)
        self.assertEqual(proc.returncode, 2)
        self.assertIn("consecutive", proc.stderr)
        self.assertEqual(written(self.tmp), [])

    def test_warmup_chunks_match_the_single_run(self):
        single, chunked, cold = self.dir("single"), self.dir("chunked"), self.dir("cold")
        self.bmfr(single, "1-6")
        self.bmfr(chunked, "1-3")
        proc = self.bmfr(chunked, "4-6", "--warmup", "3")
        self.assertIn("3 read for history only", proc.stderr)
        self.bmfr(cold, "4-6")  # no warm-up: the history starts at frame 4
        for f in (4, 5, 6):
            name = "o_%04d.exr" % f
            np.testing.assert_array_equal(pixels(os.path.join(chunked, name)), pixels(os.path.join(single, name)))
        self.assertGreater(np.abs(pixels(os.path.join(cold, "o_0004.exr")) -
                                  pixels(os.path.join(single, "o_0004.exr"))).max(), 1e-3)
        # Warm-up frames must exist: frame 0 does not.
        proc = self.bmfr(self.dir("early"), "1-2", "--warmup", "1", check=False)
        self.assertEqual(proc.returncode, 2)
        self.assertIn("anim_1spp_0000.exr", proc.stderr)
        self.assertIn("--warmup", proc.stderr)

    def test_resume_replays_only_what_history_needs(self):
        out = self.dir("out")
        self.bmfr(out, "1-6")
        want = pixels(os.path.join(out, "o_0006.exr"))
        stats = {f: os.stat(os.path.join(out, f)) for f in written(out)}
        proc = self.bmfr(out, "1-6", "--resume")  # all done: nothing read
        self.assertIn("0 written, 6 already done", proc.stderr)
        self.assertNotIn("warm-up", proc.stderr)
        os.remove(os.path.join(out, "o_0006.exr"))
        os.remove(os.path.join(out, "o_0003.exr"))
        proc = self.bmfr(out, "1-6", "--resume")  # 1-2 replayed, 3 written, 4-5 replayed, 6 written
        self.assertIn("2 written, 4 already done, 4 read for history only", proc.stderr)
        np.testing.assert_array_equal(pixels(os.path.join(out, "o_0006.exr")), want)
        for f in ("o_0001.exr", "o_0002.exr", "o_0004.exr", "o_0005.exr"):
            st = os.stat(os.path.join(out, f))
            self.assertEqual((st.st_ino, st.st_mtime_ns), (stats[f].st_ino, stats[f].st_mtime_ns), f)

    def test_a_requeued_chunk_gives_its_first_runs_pixels(self):
        """A chunk with warm-up that lost frames redoes them with the history of its whole run:
        from the warm-up frames before the chunk, through its done frames."""
        out = self.dir("out")
        self.bmfr(out, "4-7", "--warmup", "3")
        want = {f: pixels(os.path.join(out, f)) for f in written(out)}
        os.remove(os.path.join(out, "o_0006.exr"))
        os.remove(os.path.join(out, "o_0007.exr"))
        proc = self.bmfr(out, "4-7", "--warmup", "3", "--resume")
        self.assertIn("2 written, 2 already done, 5 read for history only", proc.stderr)  # 1-3 and 4-5
        for f in ("o_0006.exr", "o_0007.exr"):
            np.testing.assert_array_equal(pixels(os.path.join(out, f)), want[f], f)

    def test_resume_redoes_outputs_of_another_run(self):
        src = self.sequence(3)
        out = self.dir("out")
        pattern = os.path.join(out, "o_####.exr")
        base = ["denoise", src, "-o", pattern, "--frames", "1-3"]
        tu.run_cli(*base, "-f", "box")
        proc = tu.run_cli(*base, "-f", "box", "--resume")
        self.assertIn("0 written, 3 already done", proc.stderr)
        proc = tu.run_cli(*base, "-f", "gaussian", "--resume")
        self.assertIn("made by box, this run is gaussian", proc.stderr)
        self.assertIn("3 written", proc.stderr)
        proc = tu.run_cli(*base, "-f", "gaussian", "--set", "sigma=2", "--resume")
        self.assertIn("made with other parameters", proc.stderr)
        self.assertIn("3 written", proc.stderr)
        # Frame 2 re-rendered (another size): its output is redone, the others kept.
        tu.write_exr(src.replace("####", "0002"), np.ones((7, 9, 4), np.float32))
        proc = tu.run_cli(*base, "-f", "gaussian", "--set", "sigma=2", "--resume")
        self.assertIn("made from another input", proc.stderr)
        self.assertIn("1 written, 2 already done", proc.stderr)
        # A file mcrecon did not write is not taken for done.
        tu.write_exr(pattern.replace("####", "0003"), np.zeros((10, 12, 4), np.float32))
        proc = tu.run_cli(*base, "-f", "gaussian", "--set", "sigma=2", "--resume")
        self.assertIn("not an mcrecon output", proc.stderr)
        self.assertIn("1 written, 2 already done", proc.stderr)
        self.assertGreater(pixels(pattern.replace("####", "0003")).max(), 0)

    def test_pipelined_run_equals_the_serial_one(self):
        piped, serial = self.dir("piped"), self.dir("serial")
        proc = self.bmfr(piped, "1-5", "--timings", "--pipelined")
        lines = [ln for ln in proc.stderr.splitlines() if "o_000" in ln and "filter " in ln]
        # The frame number after the output's own name (the temp folder's random name may hold "o_").
        self.assertEqual([re.search(r"[/\\]o_(\d{4})\.exr", ln).group(1) for ln in lines],
                         ["0001", "0002", "0003", "0004", "0005"])
        self.bmfr(serial, "1-5", "--serial")
        self.assertEqual(written(piped), written(serial))
        for f in written(serial):
            np.testing.assert_array_equal(pixels(os.path.join(piped, f)), pixels(os.path.join(serial, f)), f)

    def test_a_bad_frame_stops_the_pipeline_with_every_earlier_output_complete(self):
        src = self.sequence(5, 64, 48)
        bad = src.replace("####", "0003")
        with open(bad, "rb") as f:
            data = f.read()
        with open(bad, "wb") as f:
            f.write(data[:len(data) // 2])
        out = self.dir("out")
        proc = tu.run_cli("denoise", src, "-o", os.path.join(out, "o_####.exr"), "-f", "box", "--frames", "1-5",
                          "--pipelined", check=False)
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("s_0003.exr", proc.stderr)
        self.assertEqual(os.listdir(out).__len__(), len(written(out)))  # no temp file left
        self.assertEqual(written(out), ["o_0001.exr", "o_0002.exr"])
        for f in written(out):
            self.assertEqual(pixels(os.path.join(out, f)).shape, (48, 64, 4))

    def test_plan_commands_give_the_single_run(self):
        single, farm = self.dir("single"), self.dir("farm")
        self.bmfr(single, "1-6")
        cmd = ["denoise", ANIM, "-o", os.path.join(farm, "o_####.exr"), "-f", "bmfr"]
        lines = tu.run_cli("plan", "--frames", "1-6", "--chunk", "2", "--warmup", "8", "--exe", tu.mcrecon_bin(),
                           "--", *cmd).stdout.splitlines()
        self.assertEqual(len(lines), 3)
        self.assertIn("--frames 1-2 --resume", lines[0])
        self.assertIn("--frames 5-6 --warmup 4 --resume", lines[2])  # only the frames that exist before
        for line in reversed(lines):  # chunks are independent: any order
            subprocess.run(shlex.split(line), check=True, capture_output=True, timeout=300)
        for f in written(single):
            np.testing.assert_array_equal(pixels(os.path.join(farm, f)), pixels(os.path.join(single, f)), f)
        task = tu.run_cli_json("plan", "--frames", "1-6", "--chunk", "4", "--warmup", "8", "--task", "2", "--json",
                               "--", *cmd)
        self.assertEqual([(t["task"], t["frames"], t["warmup"]) for t in task], [(2, "5-6", 4)])
        proc = tu.run_cli("plan", "--frames", "1-6", "--chunk", "2", "--", *cmd, "--resume", check=False)
        self.assertEqual(proc.returncode, 2)
        self.assertIn("--resume", proc.stderr)
        # A filter or setting the task would refuse is refused before anything is queued.
        for bad, named in ((["-f", "nosuch"], "nosuch"), (["-f", "bmfr", "--set", "block_size=-3"], "block_size")):
            proc = tu.run_cli("plan", "--frames", "1-6", "--chunk", "2", "--", "denoise", ANIM, "-o",
                              os.path.join(farm, "x_####.exr"), *bad, check=False)
            self.assertEqual(proc.returncode, 2, bad)
            self.assertIn(named, proc.stderr)


if __name__ == "__main__":
    unittest.main()
