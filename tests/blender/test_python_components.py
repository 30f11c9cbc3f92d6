"""The `mcrecon` Python module with components='light_passes' (run with Debian's /usr/bin/python3 by
ctest as blender_python_components): on a synthetic multilayer EXR with every light pass
(tests/python/light_passes_testutil.py), denoise_file and Session.denoise_file with
keep_components=True write what `mcrecon denoise --set components=light_passes --keep-components`
writes, bit for bit (beauty and every component layer); the notes say components were used;
keep_components without light passes and a missing light pass raise mcrecon.Error naming them.
Environment: MCRECON_BIN, MCRECON_SOURCE_DIR, MCRECON_PYTHON_DIR (the module's folder).
"""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
from module_testutil import expect_error, mcrecon  # noqa: E402
import light_passes_testutil as lp  # noqa: E402
import mcrecon_testutil as tu  # noqa: E402

BIN = os.environ["MCRECON_BIN"]
CHANNELS = ["R", "G", "B"] + [c for n in lp.LAYERS for c in lp.component_layer_channels(n)]


def same_bits(a, b):
    return a.shape == b.shape and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def main():
    tmp = tempfile.mkdtemp(prefix="mcrecon_pycomp_")
    try:
        passes = lp.make_passes()
        src = os.path.join(tmp, "render.exr")
        lp.write_multilayer(src, passes)
        want = os.path.join(tmp, "cli.exr")
        subprocess.run([BIN, "denoise", "-f", "atrous", "--set", "components=light_passes", "--keep-components",
                        src, "-o", want], check=True, capture_output=True, timeout=300)
        ref = tu.read_channels(want, CHANNELS)

        got = os.path.join(tmp, "module.exr")
        t = mcrecon.denoise_file(src, got, "atrous", {"components": "light_passes"}, keep_components=True)
        assert same_bits(tu.read_channels(got, CHANNELS), ref), "denoise_file differs from the CLI"
        assert any("components=light_passes" in n for n in t["notes"]), t["notes"]
        assert any(n.startswith("glossy direct: ") for n in t["notes"]), t["notes"]

        s = mcrecon.Session("atrous", {"components": "light_passes"})
        assert s.params["components"] == "light_passes" and s.params["demodulate"] is False, s.params
        assert "diffuse_direct" in s.needs()["required"], s.needs()
        got2 = os.path.join(tmp, "session.exr")
        s.denoise_file(src, got2, keep_components=True)
        assert same_bits(tu.read_channels(got2, CHANNELS), ref), "Session.denoise_file differs from the CLI"

        # Without keep_components: the same beauty, no component layers.
        got3 = os.path.join(tmp, "beauty_only.exr")
        mcrecon.denoise_file(src, got3, "atrous", {"components": "light_passes"})
        assert same_bits(tu.read_channels(got3, ["R", "G", "B"]), ref[..., :3])
        try:
            tu.read_channels(got3, lp.component_layer_channels("Diffuse"))
            raise AssertionError("component layers written without keep_components")
        except KeyError:
            pass

        expect_error(lambda: mcrecon.denoise_file(src, os.path.join(tmp, "x.exr"), "box", keep_components=True),
                     "invalid_argument", "components=light_passes")
        broken = os.path.join(tmp, "no_trans.exr")
        lp.write_multilayer(broken, passes, leave_out=("TransCol",))
        expect_error(lambda: mcrecon.denoise_file(broken, os.path.join(tmp, "y.exr"), "box",
                                                  {"components": "light_passes"}),
                     "missing_pass", "TransCol", "no_trans.exr")
        expect_error(lambda: mcrecon.Session("box", {"components": "lights"}), "parameter_out_of_range", "lights")
        assert not os.path.exists(os.path.join(tmp, "x.exr")) and not os.path.exists(os.path.join(tmp, "y.exr"))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("python module components: ok")


if __name__ == "__main__":
    main()
