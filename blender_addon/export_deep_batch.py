"""Per-sample export without the UI (issue 17): renders the current (or given) frame of a .blend
as K 1-spp sub-renders and writes the deep EXR that `mcrecon denoise -f sweep` reads.

    blender -b shot.blend --python export_deep_batch.py -- OUT.exr [--samples 16] [--frame 12]
        [--addon-dir DIR]

The add-on must be installed and enabled (Preferences), or --addon-dir names the folder that
holds mcrecon_addon/ (a build's blender_addon/stage). Exit status 1 on any error, with the
reason on stderr."""
import argparse
import os
import sys

import addon_utils
import bpy


def main(argv):
    ap = argparse.ArgumentParser(prog="export_deep_batch.py")
    ap.add_argument("output")
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--frame", type=int, default=None)
    ap.add_argument("--addon-dir", default=None)
    a = ap.parse_args(argv)
    if a.addon_dir:
        sys.path.insert(0, os.path.abspath(a.addon_dir))
    addon_utils.enable("mcrecon_addon", default_set=False, handle_error=None)
    if not hasattr(bpy.ops.mcrecon, "export_deep"):
        sys.exit("mcrecon add-on not found: install it, or pass --addon-dir")
    scene = bpy.context.scene
    if a.frame is not None:
        scene.frame_set(a.frame)
    result = bpy.ops.mcrecon.export_deep(filepath=os.path.abspath(a.output), samples=a.samples)
    if result != {"FINISHED"}:
        sys.exit(f"export_deep failed ({', '.join(sorted(result))}); see the messages above")


main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
