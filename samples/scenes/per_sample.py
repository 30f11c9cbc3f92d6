"""Per-sample (deep) form of a sample scene, for `sweep` (issue 17): the deep EXR from the
add-on's export (K one-sample sub-renders) and a reference at many samples with the same 0.01 px
pixel filter (every sample at the pixel centre, as in the deep file), raw Combined.

    blender -b --factory-startup --python-exit-code 1 --python per_sample.py -- \\
        --scene SCENE --out DIR --addon-dir build/blender_addon/stage \\
        [--spp 16] [--ref-spp 1024] [--width 128] [--height 96] [--draw N]

SCENE: a scene module of this folder: dof, motion, dof_garden, dof_spheres are the per-sample sample
scenes (samples/data/per_sample); any still's works too (sunlit, fence, jewel, ...: held-out
per-sample renders, session 33). Writes DIR/<scene>_<spp>spp_deep.exr and DIR/<scene>_ref.exr (none
with --ref-spp 0), and prints one JSON line ("per_sample": ...) with the render times. --draw N > 0
renders another draw of the samples (other seeds) as DIR/<scene>_<spp>spp_draw<N>_deep.exr, to test
a setting on samples nothing was chosen on; the reference is the same scene's."""
import argparse
import importlib
import json
import os
import sys
import time

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="per_sample.py")
    p.add_argument("--scene", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--addon-dir", required=True, help="the folder holding mcrecon_addon/ (a build's stage)")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--ref-spp", type=int, default=1024)
    p.add_argument("--width", type=int, default=128)
    p.add_argument("--height", type=int, default=96)
    p.add_argument("--draw", type=int, default=0, help="another draw of the samples: N > 0 seeds (and names) them apart")
    a = p.parse_args(argv)
    sys.path.insert(0, os.path.abspath(a.addon_dir))
    addon_utils.enable("mcrecon_addon", default_set=False, handle_error=None)
    mod = importlib.import_module(a.scene)
    scene = mod.build()
    vl = C.configure_render(scene, a.width, a.height)
    C.set_passes(vl, False)
    if hasattr(mod, "configure"):
        mod.configure(scene)
    os.makedirs(a.out, exist_ok=True)
    times = {}
    draw = f"_draw{a.draw}" if a.draw else ""
    scene.cycles.seed = C.seed_for(a.scene + draw, "deep", a.spp)
    t0 = time.time()
    deep = os.path.join(os.path.abspath(a.out), f"{a.scene}_{a.spp}spp{draw}_deep.exr")
    result = bpy.ops.mcrecon.export_deep(filepath=deep, samples=a.spp)
    if result != {"FINISHED"}:
        sys.exit(f"export_deep failed: {result}")
    times["deep"] = round(time.time() - t0, 3)
    if a.ref_spp <= 0:
        print("per_sample: " + json.dumps({"scene": a.scene, "width": a.width, "height": a.height, "spp": a.spp,
                                           "draw": a.draw, "seconds": times}), flush=True)
        return
    # The reference: the same pixel filter, many samples, raw Combined.
    scene.cycles.seed = C.seed_for(a.scene, "ref", a.ref_spp)
    scene.cycles.samples = a.ref_spp
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.filter_width = 0.01
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.filepath = os.path.join(os.path.abspath(a.out), f"{a.scene}_ref")
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    times["ref"] = round(time.time() - t0, 3)
    print("per_sample: " + json.dumps({"scene": a.scene, "width": a.width, "height": a.height, "spp": a.spp,
                                       "ref_spp": a.ref_spp, "seconds": times}), flush=True)


main()
