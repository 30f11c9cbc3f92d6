"""The output guard end to end: the CLI, the Python module, the OpenImageIO output plugin (through
oiiotool) and the Blender add-on's output naming (a pure function, no bpy).

Every refused case checks the exit status or exception kind, that the message names the path,
that every input is byte-identical afterwards and that no output or `.mcrecon-tmp.` file is left.
Environment (ctest): MCRECON_BIN, MCRECON_SOURCE_DIR, MCRECON_PYTHON_DIR (the module's folder),
MCRECON_PLUGIN_DIR (mcrecon.imageio.so's); the module and plugin cases skip when those are missing.
Device nodes are private ones made with mknod in a temp folder (root only; skipped otherwise),
never the real /dev/null.
"""
import importlib.util
import os
import resource
import shutil
import stat
import subprocess
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mcrecon_testutil as tu  # noqa: E402

SRC = tu.source_dir()
TEMP_MARK = ".mcrecon-tmp."
OIIOTOOL = shutil.which("oiiotool") or "/usr/bin/oiiotool"


def python_module():
    d = os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(SRC, "build", "python")
    if not os.path.isdir(d) or not any(n.startswith("mcrecon.") and n.endswith(".so") for n in os.listdir(d)):
        raise unittest.SkipTest("no mcrecon module in %s (set MCRECON_PYTHON_DIR)" % d)
    if d not in sys.path:
        sys.path.insert(0, d)
    import mcrecon
    return mcrecon


def plugin_dir():
    d = os.environ.get("MCRECON_PLUGIN_DIR") or os.path.join(SRC, "build", "lib")
    if not os.path.exists(os.path.join(d, "mcrecon.imageio.so")):
        raise unittest.SkipTest("no mcrecon.imageio.so in %s (set MCRECON_PLUGIN_DIR)" % d)
    return d


def output_paths():
    """The add-on's output naming, loaded without the package (its __init__ needs bpy)."""
    path = os.path.join(SRC, "blender_addon", "mcrecon_addon", "output_paths.py")
    spec = importlib.util.spec_from_file_location("mcrecon_output_paths", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def listing(d):
    return sorted(os.listdir(d))


def noise(h, w, c, seed):
    return np.random.default_rng(seed).random((h, w, c), dtype=np.float32)


class GuardCase(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="mcrecon_guard_")
        self.addCleanup(shutil.rmtree, self.dir, True)
        self.inp = self.path("in.exr")
        tu.write_exr(self.inp, noise(12, 16, 4, 1), ["R", "G", "B", "A"])
        self.normal = self.path("n.exr")
        tu.write_exr(self.normal, noise(12, 16, 3, 2), ["R", "G", "B"])

    def path(self, *names):
        return os.path.join(self.dir, *names)

    def snapshot(self):
        """Every regular file in the folder (recursively) with its bytes."""
        out = {}
        for root, _, files in os.walk(self.dir):
            for n in files:
                p = os.path.join(root, n)
                if stat.S_ISREG(os.lstat(p).st_mode):
                    with open(p, "rb") as f:
                        out[os.path.relpath(p, self.dir)] = f.read()
        return out

    def assert_untouched(self, before, names=None):
        """Inputs byte-identical, no new file, no temp anywhere (names: the listing expected)."""
        after = self.snapshot()
        self.assertEqual(after, before)
        for root, _, files in os.walk(self.dir):
            self.assertFalse([n for n in files if TEMP_MARK in n], root)
        if names is not None:
            self.assertEqual(listing(self.dir), sorted(names))

    def device_node(self, name="null"):
        p = self.path(name)
        try:
            os.mknod(p, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        except PermissionError:
            self.skipTest("mknod needs root")
        return p

    def cli_refused(self, args, *named, status=2):
        before = self.snapshot()
        names = listing(self.dir)
        proc = tu.run_cli(*args, check=False)
        self.assertEqual(proc.returncode, status, proc.stderr)
        self.assertIn("mcrecon: error:", proc.stderr)
        for n in named:
            self.assertIn(n, proc.stderr)
        self.assert_untouched(before, names)
        return proc.stderr


class CliGuard(GuardCase):
    def test_output_is_an_input_in_any_spelling(self):
        os.symlink(self.inp, self.path("link.exr"))
        os.link(self.inp, self.path("hard.exr"))
        os.mkdir(self.path("sub"))
        for out in (self.inp, os.path.join(self.dir, ".", "in.exr"), self.path("sub", "..", "in.exr"),
                    self.path("link.exr"), self.path("hard.exr")):
            with self.subTest(out=out):
                err = self.cli_refused(["denoise", self.inp, "-o", out, "-f", "box"], out, "never overwritten")
                self.assertIn(self.inp, err)
        self.cli_refused(["denoise", self.inp, "--pass", "normal=" + self.normal, "-o", self.normal, "-f", "box"],
                         self.normal, "never overwritten")

    def test_device_fifo_and_directory_outputs_are_refused(self):
        node = self.device_node()
        fifo = self.path("fifo")
        os.mkfifo(fifo)
        os.mkdir(self.path("sub"))
        for out, kind in ((node, "character device"), (fifo, "FIFO"), (self.path("sub"), "directory")):
            with self.subTest(out=out):
                self.cli_refused(["denoise", self.inp, "-o", out, "-f", "box"], "'%s'" % out, kind, "regular file")
        self.assertTrue(stat.S_ISCHR(os.lstat(node).st_mode))
        self.assertTrue(stat.S_ISFIFO(os.lstat(fifo).st_mode))

    def make_frames(self, n):
        for f in range(1, n + 1):
            tu.write_exr(self.path("f_%04d.exr" % f), noise(6, 8, 4, 10 + f), ["R", "G", "B", "A"])

    def test_wide_frame_number_gives_every_frame_its_file(self):
        self.make_frames(2)
        out = self.path("o_" + "#" * 40 + ".exr")
        proc = tu.run_cli("denoise", self.path("f_####.exr"), "--frames", "1-2", "-o", out, "-f", "box")
        self.assertIn("2 written", proc.stderr)
        outs = ["o_" + "0" * 39 + "%d.exr" % f for f in (1, 2)]
        self.assertTrue(set(outs) <= set(listing(self.dir)), listing(self.dir))
        a, b = (tu.read_channels(self.path(o), ["R"]) for o in outs)
        self.assertFalse(np.array_equal(a, b))  # each frame's own result

    def test_frames_sharing_one_output_are_refused(self):
        self.make_frames(2)
        os.mkdir(self.path("d_0001"))
        pattern = self.path("d_####", "..", "out.exr")
        self.cli_refused(["denoise", self.path("f_####.exr"), "--frames", "1-2", "-o", pattern, "-f", "box"],
                         pattern, "frames 1 and 2")
        self.cli_refused(["denoise", self.path("f_####.exr"), "--frames", "1-2", "-o",
                          os.path.join(self.dir, ".", "f_####.exr"), "-f", "box"], "f_0001.exr", "never overwritten")

    def test_concurrent_runs_on_one_output_all_succeed(self):
        want = self.path("want.exr")
        tu.run_cli("denoise", self.inp, "-o", want, "-f", "box")
        os.mkdir(self.path("o"))
        out = self.path("o", "out.exr")
        procs = [subprocess.Popen([tu.mcrecon_bin(), "denoise", self.inp, "-o", out, "-f", "box"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(8)]
        for p in procs:
            _, err = p.communicate(timeout=120)
            self.assertEqual(p.returncode, 0, err)
        self.assertEqual(listing(self.path("o")), ["out.exr"])
        rgba = ["R", "G", "B", "A"]
        self.assertTrue(np.array_equal(tu.read_channels(out, rgba), tu.read_channels(want, rgba)))

    def test_longest_output_name_is_written(self):
        for n in (254, 255):
            name = "o" * (n - 4) + ".exr"
            tu.run_cli("denoise", self.inp, "-o", self.path(name), "-f", "box")
            self.assertIn(name, listing(self.dir))
            self.assertFalse([f for f in listing(self.dir) if TEMP_MARK in f])

    def test_file_size_limit_is_an_error_and_leaves_no_temp(self):
        big = self.path("big.exr")
        tu.write_exr(big, noise(64, 64, 4, 3), ["R", "G", "B", "A"])
        before, names = self.snapshot(), listing(self.dir)
        out = self.path("out.exr")

        def limit():
            resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
        proc = subprocess.run([tu.mcrecon_bin(), "denoise", big, "-o", out, "-f", "box", "--compression", "none"],
                              capture_output=True, text=True, timeout=120, preexec_fn=limit)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        self.assertIn("'%s'" % out, proc.stderr)
        self.assertIn("file size limit", proc.stderr)
        self.assert_untouched(before, names)

    def test_disk_full_says_so(self):
        mnt = self.path("small")
        os.mkdir(mnt)
        if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", mnt], capture_output=True).returncode:
            self.skipTest("cannot mount a tmpfs here")
        self.addCleanup(subprocess.run, ["umount", "-l", mnt])
        big = self.path("big.exr")
        tu.write_exr(big, noise(128, 128, 4, 4), ["R", "G", "B", "A"])
        out = os.path.join(mnt, "out.exr")
        proc = tu.run_cli("denoise", big, "-o", out, "-f", "box", "--compression", "none", check=False)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        self.assertIn("cannot write '%s': the disk is full (No space left on device)" % out, proc.stderr)
        self.assertEqual(os.listdir(mnt), [])


class ModuleGuard(GuardCase):
    def setUp(self):
        self.mc = python_module()
        super().setUp()

    def refused(self, fn, kind, *named):
        before, names = self.snapshot(), listing(self.dir)
        with self.assertRaises(self.mc.Error) as cm:
            fn()
        self.assertEqual(cm.exception.kind, kind, str(cm.exception))
        for n in named:
            self.assertIn(n, str(cm.exception))
        self.assert_untouched(before, names)

    def test_denoise_file_never_writes_over_its_input(self):
        mc = self.mc
        os.symlink(self.inp, self.path("link.exr"))
        for out in (self.inp, os.path.join(self.dir, ".", "in.exr"), self.path("link.exr")):
            with self.subTest(out=out):
                self.refused(lambda: mc.denoise_file(self.inp, out, "box"), "invalid_argument", out)
                self.refused(lambda: mc.Session("box").denoise_file(self.inp, out), "invalid_argument", out)
        self.refused(lambda: mc.denoise_file(self.inp, self.normal, "box", passes={"normal": self.normal}),
                     "invalid_argument", self.normal)

    def test_device_output_is_refused(self):
        node = self.device_node()
        self.refused(lambda: self.mc.denoise_file(self.inp, node, "box"), "write_failed", node, "character device")
        self.assertTrue(stat.S_ISCHR(os.lstat(node).st_mode))

    def test_denoise_sequence_checks_every_frame_first(self):
        mc = self.mc
        for f in (1, 2):
            tu.write_exr(self.path("f_%04d.exr" % f), noise(6, 8, 4, 20 + f), ["R", "G", "B", "A"])
        os.mkdir(self.path("d_0001"))
        pattern = self.path("d_####", "..", "out.exr")
        self.refused(lambda: mc.denoise_sequence(self.path("f_####.exr"), pattern, 1, 2, "box"),
                     "invalid_argument", pattern, "frames 1 and 2")
        # frame 2's output is frame 2's input: refused before frame 1 is written
        self.refused(lambda: mc.denoise_sequence(self.path("f_####.exr"), self.path("f_%04d.exr"), 1, 2, "box"),
                     "invalid_argument", "f_0001.exr")
        outs = mc.denoise_sequence(self.path("f_####.exr"), self.path("o_" + "#" * 40 + ".exr"), 1, 2, "box")
        self.assertEqual(len(set(outs)), 2)
        self.assertTrue(all(os.path.exists(o) for o in outs))


class PluginGuard(GuardCase):
    def oiiotool(self, *args):
        env = dict(os.environ, OIIO_LIBRARY_PATH=plugin_dir())
        return subprocess.run([OIIOTOOL, *args], capture_output=True, text=True, timeout=120, env=env)

    def test_device_output_is_refused(self):
        plugin_dir()
        node = self.device_node()
        before, names = self.snapshot(), listing(self.dir)
        proc = self.oiiotool(self.inp, "--attrib", "mcrecon:filter", "box", "-o:fileformatname=mcrecon", node)
        self.assertNotEqual(proc.returncode, 0, proc.stdout + proc.stderr)
        err = proc.stdout + proc.stderr
        self.assertIn(node, err)
        self.assertIn("character device", err)
        self.assertTrue(stat.S_ISCHR(os.lstat(node).st_mode))
        self.assert_untouched(before, names)

    def test_regular_output_is_written(self):
        plugin_dir()
        out = self.path("out.exr")
        proc = self.oiiotool(self.inp, "--attrib", "mcrecon:filter", "box", "-o:fileformatname=mcrecon", out)
        self.assertEqual(proc.returncode, 0, proc.stdout + proc.stderr)
        self.assertEqual(tu.read_channels(out, ["R", "G", "B", "A"]).shape, (12, 16, 4))
        self.assertFalse([n for n in listing(self.dir) if TEMP_MARK in n or ".temp" in n])


class AddonOutputNames(unittest.TestCase):
    def test_animation_without_hashes_numbers_every_frame(self):
        op = output_paths()
        self.assertEqual(op.output_for_frame("/r/out.exr", 3, True), "/r/out0003.exr")
        self.assertEqual(op.output_for_frame("/r/out", 12, True), "/r/out0012.exr")
        self.assertEqual(op.output_for_frame("/r/out.exr", 3, False), "/r/out.exr")  # a still
        self.assertEqual(op.output_for_frame("/r/o_##.exr", 3, True), "/r/o_03.exr")
        self.assertEqual(op.output_for_frame("/r/o_##.exr", 3, False), "/r/o_03.exr")
        # The render's format when the name has none mcrecon writes; a name's own format kept.
        self.assertEqual(op.output_for_frame("/r/out", 2, True, ".png"), "/r/out0002.png")
        self.assertEqual(op.output_for_frame("/r/out.tif", 2, True, ".png"), "/r/out0002.tif")
        self.assertEqual(op.output_for_frame("/r/out.v2", 2, False, ".jpg"), "/r/out.v2.jpg")
        frames = [op.output_for_frame("/r/out.exr", f, True) for f in range(1, 11)]
        self.assertEqual(len(set(frames)), 10)

    def test_a_sequence_is_found_from_one_of_its_files(self):
        op = output_paths()
        d = tempfile.mkdtemp(prefix="mcrecon_seq_")
        try:
            for name in ("shot_v2_0001.exr", "shot_v2_0002.exr", "shot_v2_0003.exr", "shot_v2_0007.exr",
                         "shot_v2_10000.exr", "shot_v2_0004.png", "shot_v2_004.exr", "other_0005.exr",
                         "shot_v2_0005.exr.bak", "shot_v2_0006_denoised.exr"):
                open(os.path.join(d, name), "w").close()
            pattern, frames = op.sequence_of(os.path.join(d, "shot_v2_0002.exr"))
            self.assertEqual(pattern, os.path.join(d, "shot_v2_####.exr"))
            self.assertEqual(frames, [1, 2, 3, 7, 10000])
            self.assertEqual(op.runs(frames), [(1, 3), (7, 7), (10000, 10000)])
            self.assertEqual(op.sequence_of(os.path.join(d, "still.exr")), (os.path.join(d, "still.exr"), []))
            self.assertEqual(op.sequence_of(os.path.join(d, "shot_v2_####.exr"))[1], [1, 2, 3, 7, 10000])
            self.assertEqual(op.sequence_of("/nowhere/s_####.exr"), ("/nowhere/s_####.exr", []))
        finally:
            shutil.rmtree(d)


if __name__ == "__main__":
    unittest.main(verbosity=2)
