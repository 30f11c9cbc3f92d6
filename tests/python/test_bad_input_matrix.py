"""The bad-input matrix (issue 13): every case of bad_input_cases.CASES through every front end it
applies to: the `mcrecon` CLI, the OpenImageIO plugin through `oiiotool` (reader, --iconfig,
writer) and the Python module `mcrecon` (in a child interpreter, so a crash or hang is caught).

For each (case, front end), in a fresh directory holding the case's inputs:
- bad input: CLI exit status 2 with `mcrecon: error:`, oiiotool a non-zero exit (no signal),
  Python `mcrecon.Error` with a .kind; the message names the file / pass / parameter and repeats
  what was given, and prints no range as hundreds of digits;
- good input (cases ending in _ok): success, exactly the expected outputs, complete and finite;
- always: every file of the directory byte-identical (and every node of the same type) afterwards,
  no output and no temp file (`.mcrecon-tmp.`, oiiotool's `.temp.`) left, and an answer within
  10 s (a hang detector, not a timing assertion).

Environment: MCRECON_BIN (CLI), MCRECON_PLUGIN_DIR (folder of mcrecon.imageio.so),
MCRECON_PYTHON_DIR (folder of the mcrecon module), MCRECON_SOURCE_DIR. A front end whose binary is
missing is skipped. MATRIX_CASES=name,name runs only those cases.
"""
import json
import os
import re
import threading
import shutil
import subprocess
import sys
import tempfile
import unittest
from concurrent.futures import ThreadPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bad_input_cases as bc  # noqa: E402
import bad_input_files as bf  # noqa: E402
import mcrecon_testutil as tu  # noqa: E402

TIMEOUT = 10
# Peak memory of one run: every input is 16x12, so more means an allocation sized by a header (or
# a count) that the file cannot justify.
PEAK_LIMIT_MB = 512
OIIOTOOL = shutil.which("oiiotool") or "/usr/bin/oiiotool"
PYTHON = "/usr/bin/python3"


def plugin_dir():
    return os.environ.get("MCRECON_PLUGIN_DIR") or os.path.join(tu.source_dir(), "build", "lib")


def python_dir():
    return os.environ.get("MCRECON_PYTHON_DIR") or os.path.join(tu.source_dir(), "build", "python")


def front_end_missing(fe):
    if fe.startswith("cli"):
        return None if os.access(tu.mcrecon_bin(), os.X_OK) else "no mcrecon CLI at %s" % tu.mcrecon_bin()
    if fe.startswith("oiio"):
        if not os.path.exists(os.path.join(plugin_dir(), "mcrecon.imageio.so")):
            return "no mcrecon.imageio.so in %s" % plugin_dir()
        return None if os.access(OIIOTOOL, os.X_OK) else "no oiiotool"
    names = os.listdir(python_dir()) if os.path.isdir(python_dir()) else []
    if not any(n.startswith("mcrecon.") and n.endswith(".so") for n in names):
        return "no mcrecon Python module in %s" % python_dir()
    return None


# Runs one statement with the module in a child interpreter; prints the outcome as JSON.
PY_RUNNER = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
import numpy as np
import mcrecon
try:
    exec(sys.argv[2], {"mcrecon": mcrecon, "np": np})
    r = {"ok": True}
except BaseException as e:
    r = {"ok": False, "type": type(e).__module__ + "." + type(e).__qualname__,
         "is_mcrecon_error": isinstance(e, mcrecon.Error), "kind": getattr(e, "kind", None), "message": str(e)}
print("@@RESULT " + json.dumps(r))
"""


class Outcome:
    """What one front end did: ok, the message, and a description for failure reports."""

    def __init__(self, fe, cmd):
        self.fe, self.cmd, self.ok, self.message, self.problem, self.log = fe, cmd, False, "", None, ""
        self.wrong_kind = None  # a refusal of the wrong kind (CLI status, Python exception type)


def run_front_end(fe, spec, c):
    if fe.startswith("py"):
        code = spec
        cmd = [PYTHON, "-c", PY_RUNNER, python_dir(), code]
        shown = "python: " + code
    elif fe.startswith("cli"):
        cmd = [tu.mcrecon_bin(), *spec]
        shown = "mcrecon " + " ".join(spec)
    else:
        cmd = [OIIOTOOL, *spec]
        shown = "oiiotool " + " ".join(spec)
    o = Outcome(fe, shown)
    env = dict(os.environ, OIIO_LIBRARY_PATH=plugin_dir())
    returncode, o.log, peak_mb, killed = spawn(cmd, c.d, env)
    problems = []
    if killed:
        problems.append("no answer within %d s (hang; killed)" % TIMEOUT)
    elif returncode < 0:
        problems.append("killed by signal %d (crash)" % -returncode)
    if peak_mb > PEAK_LIMIT_MB:
        problems.append("peak memory %d MB for 16x12 inputs (limit %d MB)" % (peak_mb, PEAK_LIMIT_MB))
    if problems:
        o.problem = "; ".join(problems)
        return o
    return _judge(fe, returncode, o)


def spawn(cmd, cwd, env):
    """Runs cmd; returns (exit code, stdout + stderr, peak RSS in MB, killed after TIMEOUT s).
    os.wait4 gives this process's own peak memory, whatever runs beside it."""
    with tempfile.TemporaryFile() as out:
        p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             cwd=cwd, env=env)
        killed = []
        timer = threading.Timer(TIMEOUT, lambda: (killed.append(True), p.kill()))
        timer.start()
        try:
            _, status, usage = os.wait4(p.pid, 0)
        finally:
            timer.cancel()
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        return p.returncode, out.read().decode(errors="replace"), usage.ru_maxrss // 1024, bool(killed)


def _judge(fe, returncode, o):
    if fe.startswith("py"):
        lines = [l for l in o.log.splitlines() if l.startswith("@@RESULT ")]
        if returncode != 0 or not lines:
            o.problem = "the interpreter exited %d without a result" % returncode
            return o
        r = json.loads(lines[-1][len("@@RESULT "):])
        o.ok, o.message, o.exc_type = r["ok"], r.get("message", ""), r.get("type")
        if not r["ok"] and not (r["is_mcrecon_error"] and r["kind"]):
            o.wrong_kind = "raised %s (kind %r), want mcrecon.Error with a .kind" % (r["type"], r["kind"])
        return o
    o.ok = returncode == 0
    o.message = o.log
    if fe.startswith("cli") and not o.ok:
        if returncode != 2:
            o.wrong_kind = "exit status %d, want 2" % returncode
        elif "mcrecon: error:" not in o.log or "internal error" in o.log:
            o.wrong_kind = "no 'mcrecon: error:' line (or an internal error)"
    return o


def missing_mentions(message, mentions):
    missing = []
    for m in mentions:
        alternatives = m if isinstance(m, tuple) else (m,)
        if not any(a in message for a in alternatives):
            missing.append(" or ".join(repr(a) for a in alternatives))
    return missing


class Run:
    """One (case, front end) executed in its own directory: the snapshots around the run."""

    def __init__(self, case, fe):
        self.case, self.fe, self.skip, self.outcome, self.c = case, fe, front_end_missing(fe), None, None
        if self.skip:
            return
        self.root = tempfile.mkdtemp(prefix="mcrecon_matrix_")
        d = os.path.join(self.root, "case")
        os.mkdir(d)
        self.c = bc.ctx(d)
        self.c.root = self.root
        try:
            case.build(self.c)
        except bc.Skip as e:
            self.skip = str(e)
            return
        self.before = bf.snapshot(d)
        self.outcome = run_front_end(fe, case.fe[fe](self.c), self.c)
        self.after = bf.snapshot(d)

    def cleanup(self):
        if self.c is not None:
            bc.cleanup(self.c)
            shutil.rmtree(self.root, ignore_errors=True)


_RUNS = {}


def selected():
    only = set(filter(None, os.environ.get("MATRIX_CASES", "").split(",")))
    return [(case, fe) for case in bc.CASES if not only or case.name in only for fe in case.fe]


def run_all():
    """Every selected (case, front end), two at a time (each run is one process, mostly start-up)."""
    if not _RUNS:
        with ThreadPoolExecutor(max_workers=2) as pool:
            for (case, fe), run in zip(selected(), pool.map(lambda k: Run(*k), selected())):
                _RUNS[case.name, fe] = run
    return _RUNS


class BadInputMatrix(unittest.TestCase):
    maxDiff = None

    def run_case(self, case, fe):
        run = run_all()[case.name, fe]
        self.addCleanup(run.cleanup)
        if run.skip:
            self.skipTest(run.skip)
        c, o, before, after = run.c, run.outcome, run.before, run.after
        head = "%s [%s]: %s\n" % (case.name, fe, o.cmd)
        tail = "\n--- output ---\n%s" % o.log[-3000:]
        if o.problem:
            self.fail(head + o.problem + tail)
        if case.expect == "ok" or (case.expect == "ok_or_refused" and o.ok):
            self.check_success(case, fe, c, o, before, after, head, tail)
        else:
            self.check_refusal(case.mentions_fe.get(fe, case.mentions), o, before, after, head, tail)

    def check_refusal(self, mentions, o, before, after, head, tail):
        self.assertFalse(o.ok, head + "succeeded, want a refusal naming %s" % (mentions,) + tail)
        self.assertIsNone(o.wrong_kind, head + "%s: %s" % (o.wrong_kind, o.message.strip()[-2000:]))
        missing = missing_mentions(o.message, mentions)
        self.assertFalse(missing, head + "the message does not name %s: %s" % (", ".join(missing), o.message.strip()))
        typed = o.message  # what the user typed may be long (10**30); anything else may not
        for m in mentions:
            for a in (m if isinstance(m, tuple) else (m,)):
                typed = typed.replace(a, "")
        self.assertIsNone(re.search(r"\d{25}", typed),
                          head + "a number printed with 25+ digits (an unreadable range): " + o.message.strip())
        diff = bf.snapshot_diff(before, after)
        self.assertEqual(diff, "", head + "the directory changed (inputs must stay byte-identical, no "
                                    "output, no temp file):\n" + diff + tail)

    def check_success(self, case, fe, c, o, before, after, head, tail):
        self.assertTrue(o.ok, head + "failed, want success:\n" + o.message.strip()[-3000:] +
                        ("\n(%s)" % o.exc_type if getattr(o, "exc_type", None) else ""))
        kept = {p: k for p, k in before.items() if p not in case.mutable}
        diff = bf.snapshot_diff(kept, {p: after[p] for p in kept if p in after})
        self.assertEqual(diff, "", head + "an input changed:\n" + diff)
        new = sorted(p for p in after if p not in before)
        want = sorted(set(case.outputs) - set(before))
        self.assertEqual(new, want, head + "wrote %s, want exactly %s" % (new, want) + tail)
        self.assertEqual(bf.temp_files(c.d), [], head + "a temp file is left")
        for name in case.outputs:
            path = c.p(name)
            try:
                w, h, px = bf.read_rgba(path)
                unreadable = None
            except AssertionError as e:
                unreadable = str(e)
            self.assertIsNone(unreadable, head + "output %s is not a complete image: %s" % (name, unreadable))
            self.assertEqual((w, h), case.size, head + "%s is %dx%d, want %dx%d" % (name, w, h, *case.size))
            bad = int(np.count_nonzero(~np.isfinite(px)))
            self.assertEqual(bad, 0, head + "%s holds %d non-finite values" % (name, bad))
            if case.nonzero:
                zeros = int(np.count_nonzero(px[..., :3] == 0))
                self.assertEqual(zeros, 0, head + "%s holds %d zero RGB values (max %g)" % (name, zeros, px[..., :3].max()))
        if case.same_as_threads0:
            self.check_same_as_threads0(case, fe, c, head)

    def check_same_as_threads0(self, case, fe, c, head):
        ref_dir = os.path.join(c.root, "ref")
        os.mkdir(ref_dir)
        ref = os.path.join(ref_dir, "out.exr")
        if fe == "py":
            spec = bc.py_file("{inp}", ref)(c)
        else:
            spec = bc.cli_denoise("{inp}", ref, "--threads", "0")(c)
        r = run_front_end(fe, spec, c)
        self.assertTrue(r.ok and not r.problem, head + "the --threads 0 reference run failed: " + r.log)
        a, b = bf.read_rgba(c.out)[2], bf.read_rgba(ref)[2]
        self.assertTrue(np.array_equal(a.view(np.uint32), b.view(np.uint32)),
                        head + "output differs from the threads=0 run (max |d| %g)" % np.abs(a - b).max())


def _add_tests():
    for case, fe in selected():
        def test(self, case=case, fe=fe):
            self.run_case(case, fe)
        test.__doc__ = "%s through %s%s" % (case.name, fe, " (%s)" % case.note if case.note else "")
        setattr(BadInputMatrix, "test_%s__%s" % (case.name, fe), test)


_add_tests()


class MatrixSize(unittest.TestCase):
    def test_at_least_40_cases_and_every_front_end(self):
        self.assertGreaterEqual(len(bc.CASES), 40)
        fes = {fe.split("_")[0] for case in bc.CASES for fe in case.fe}
        self.assertEqual(fes, {"cli", "oiio", "py"})
        names = [c.name for c in bc.CASES]
        self.assertEqual(len(names), len(set(names)), "duplicate case names")


if __name__ == "__main__":
    unittest.main(verbosity=2)
