"""`mcrecon denoise --set components=light_passes --keep-components` on a synthetic multilayer EXR
with every Blender light pass (light_passes_testutil.py).

Oracles: each component run alone through the CLI as an ordinary beauty (a file whose Combined is
that component's direct + indirect light, with the same features; glossy and transmission: its
direct and its indirect light each alone, added after filtering), multiplied by its colour pass in
numpy, plus Emit and Env, is the light_passes output; the written component layers add up to the
written beauty within 1e-5 relative per pixel; a missing light pass is refused naming it and the
file; --keep-components without light passes is refused.

Run by ctest as `/usr/bin/python3 tests/python/test_cli_components.py` with MCRECON_BIN.
"""
import json
import os
import re
import shutil
import sys
import tempfile
import unittest

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import light_passes_testutil as lp  # noqa: E402
import mcrecon_testutil as tu  # noqa: E402

RGB = ["R", "G", "B"]


class ComponentsCliTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="mcrecon_components_")
        self.addCleanup(shutil.rmtree, self.tmp, ignore_errors=True)
        self.passes = lp.make_passes()
        self.input = os.path.join(self.tmp, "render.exr")
        lp.write_multilayer(self.input, self.passes)

    def path(self, name):
        return os.path.join(self.tmp, name)

    def denoise(self, *args, check=True):
        return tu.run_cli("denoise", *args, check=check)

    def test_components_equal_each_light_filtered_alone_and_sum_to_the_beauty(self):
        for filt in ("box", "bilateral"):
            with self.subTest(filter=filt):
                out = self.path("out_%s.exr" % filt)
                proc = self.denoise("-f", filt, "--set", "components=light_passes", "--keep-components",
                                    self.input, "-o", out, "-v")
                self.assertIn("components=light_passes", proc.stderr)
                beauty = tu.read_channels(out, RGB)
                layers = {n: tu.read_channels(out, lp.component_layer_channels(n)) for n in lp.LAYERS}
                # The written layers add up to the written beauty.
                total = np.zeros_like(beauty)
                for n in lp.LAYERS:
                    total += layers[n]
                np.testing.assert_array_less(np.abs(total - beauty), 1e-5 * np.abs(beauty) + 1e-30)
                # Each component as the CLI filters an ordinary beauty, times its colour pass:
                # diffuse light as direct + indirect, glossy and transmission light as direct
                # and indirect apart, added after filtering.
                expected = self.passes["Emit"] + self.passes["Env"]
                for name, short in lp.COMPONENTS:
                    parts = ([self.passes[short + "Dir"] + self.passes[short + "Ind"]] if short == "Diff"
                             else [self.passes[short + "Dir"], self.passes[short + "Ind"]])
                    light = np.zeros_like(parts[0])
                    for i, part in enumerate(parts):
                        single = self.path("%s_%s_%d.exr" % (filt, short, i))
                        lp.write_single(single, part, self.passes, self.passes[short + "Col"])
                        self.denoise("-f", filt, single, "-o", single + ".out.exr")
                        light = light + tu.read_channels(single + ".out.exr", RGB)
                    want = light * self.passes[short + "Col"]
                    np.testing.assert_allclose(layers[name], want, rtol=1e-6, atol=1e-7, err_msg=name)
                    expected = expected + want
                np.testing.assert_array_equal(layers["Emission"], self.passes["Emit"])
                np.testing.assert_array_equal(layers["Environment"], self.passes["Env"])
                np.testing.assert_allclose(beauty, expected, rtol=1e-5, atol=1e-6)
                # And it is not the beauty filtered as a whole.
                whole = self.path("whole_%s.exr" % filt)
                self.denoise("-f", filt, self.input, "-o", whole)
                self.assertGreater(np.abs(tu.read_channels(whole, RGB) - beauty).max(), 1e-3)

    def test_a_missing_light_pass_is_named_with_the_file(self):
        broken = self.path("no_gloss.exr")
        lp.write_multilayer(broken, self.passes, leave_out=("GlossInd", "Env"))
        proc = self.denoise("-f", "box", "--set", "components=light_passes", broken, "-o", self.path("o.exr"),
                            check=False)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        for text in ("GlossInd (glossy_indirect)", "Env (environment)", "no_gloss.exr", "components=light_passes"):
            self.assertIn(text, proc.stderr)
        self.assertNotIn("DiffDir", proc.stderr)
        self.assertFalse(os.path.exists(self.path("o.exr")))

    def test_keep_components_needs_light_passes_and_bad_values_are_refused(self):
        proc = self.denoise("-f", "box", "--keep-components", self.input, "-o", self.path("o.exr"), check=False)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        self.assertIn("components=light_passes", proc.stderr)
        proc = self.denoise("-f", "atrous", "--set", "components=lights", self.input, "-o", self.path("o.exr"),
                            check=False)
        self.assertEqual(proc.returncode, 2, proc.stderr)
        for text in ("lights", "beauty", "light_passes"):
            self.assertIn(text, proc.stderr)

    def test_half_buffers_merge_every_light_pass(self):
        # Two halves are their mean, light passes included (Blender accumulates them over the
        # samples): the result is the light_passes run on one file of the averaged passes.
        other = self.path("other_half.exr")
        second = lp.make_passes(seed=2)
        lp.write_multilayer(other, second)
        mean = {k: (0.5 * self.passes[k] + 0.5 * second[k]).astype(np.float32) for k in self.passes}
        mean["Depth"] = self.passes["Depth"]  # written from the first sample: the first half's
        merged = self.path("merged.exr")
        lp.write_multilayer(merged, mean)
        for filt in ("box", "bilateral"):
            with self.subTest(filter=filt):
                got, want = self.path("halves_%s.exr" % filt), self.path("merged_%s.exr" % filt)
                self.denoise("-f", filt, "--set", "components=light_passes", self.input, "--half", other, "-o", got)
                self.denoise("-f", filt, "--set", "components=light_passes", merged, "-o", want)
                a, b = tu.read_channels(got, RGB), tu.read_channels(want, RGB)
                np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-6)
                # Not the first half's light alone.
                first = self.path("first_%s.exr" % filt)
                self.denoise("-f", filt, "--set", "components=light_passes", self.input, "-o", first)
                self.assertGreater(np.abs(tu.read_channels(first, RGB) - a).max(), 1e-2)

    def test_every_filter_takes_components(self):
        listing = tu.run_cli_json("filters", "--json")
        filters = listing["filters"]
        names = [f["name"] for f in filters]
        self.assertIn("auto", names)
        for f in filters:
            self.assertIn("components", [p["name"] for p in f["parameters"]], f["name"])
        out = self.path("auto.exr")
        proc = self.denoise("-f", "auto", "--set", "components=light_passes", "--keep-components", self.input,
                            "-o", out, "-v", "--json")
        self.assertIn("diffuse: auto:", proc.stderr)
        self.assertIn("glossy direct: auto:", proc.stderr)
        self.assertIn("transmission indirect: auto:", proc.stderr)
        # What auto ran in each light stage: the --json record and the header say what the notes say.
        said = dict(re.findall(r": ([a-z ]+): auto: chose (?:the )?(\S+)", proc.stderr))
        stages = ["diffuse", "glossy direct", "glossy indirect", "transmission direct", "transmission indirect"]
        self.assertEqual(sorted(said), sorted(stages), proc.stderr)
        self.assertEqual(json.loads(proc.stdout)["chosen"], said)
        inp = oiio.ImageInput.open(out)
        self.assertEqual(inp.spec().get_string_attribute("mcreconChosen"),
                         "; ".join("%s=%s" % (s, said[s]) for s in stages))
        inp.close()


if __name__ == "__main__":
    unittest.main()
