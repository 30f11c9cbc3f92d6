"""The OpenImageIO plugin with components=light_passes: on a synthetic multilayer EXR with every
light pass (tests/python/light_passes_testutil.py), the `?components=light_passes` input name and the
output plugin with mcrecon:components / mcrecon:keep_components give what
`mcrecon denoise --set components=light_passes [--keep-components]` writes, bit for bit; a missing
light pass is an error naming it.

Run by ctest as `/usr/bin/python3 tests/plugin/test_plugin_components.py` with MCRECON_BIN and
MCRECON_PLUGIN_DIR.
"""
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "python"))
import light_passes_testutil as lp  # noqa: E402
import mcrecon_testutil as tu  # noqa: E402
from test_plugin_oiio import check_ok, oiiotool, same_bits  # noqa: E402

LAYERS = [c for n in lp.LAYERS for c in lp.component_layer_channels(n)]


class PluginComponentsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_plugin_comp_")
        self.addCleanup(shutil.rmtree, self.tmp, ignore_errors=True)
        self.passes = lp.make_passes()
        self.src = os.path.join(self.tmp, "render.exr")
        lp.write_multilayer(self.src, self.passes)

    def path(self, name):
        return os.path.join(self.tmp, name)

    def test_input_name_and_output_plugin_match_the_cli(self):
        want = self.path("cli.exr")
        tu.run_cli("denoise", "-f", "box", "--set", "components=light_passes", "--keep-components", self.src,
                   "-o", want)
        rgb = tu.read_channels(want, ["R", "G", "B"])
        got = self.path("in_name.exr")
        check_ok(oiiotool(self.src + ".mcrecon?filter=box&components=light_passes", "-o", got))
        self.assertTrue(same_bits(tu.read_channels(got, ["R", "G", "B"]), rgb), "?components=light_passes")
        got = self.path("out_plugin.exr")
        check_ok(oiiotool(self.src, "--attrib", "mcrecon:filter", "box", "--attrib", "mcrecon:components",
                          "light_passes", "--attrib", "mcrecon:keep_components", "1", "-o:fileformatname=mcrecon", got))
        self.assertTrue(same_bits(tu.read_channels(got, ["R", "G", "B"]), rgb), "output plugin beauty")
        self.assertTrue(same_bits(tu.read_channels(got, LAYERS), tu.read_channels(want, LAYERS)),
                        "output plugin component layers")

    def test_missing_light_pass_is_named(self):
        broken = self.path("no_env.exr")
        lp.write_multilayer(broken, self.passes, leave_out=("Env",))
        proc = oiiotool(broken + ".mcrecon?filter=box&components=light_passes", "-o", self.path("o.exr"))
        self.assertNotEqual(proc.returncode, 0)
        self.assertIn("Env (environment)", proc.stdout + proc.stderr)
        self.assertIn("components=light_passes", proc.stdout + proc.stderr)


if __name__ == "__main__":
    unittest.main()
