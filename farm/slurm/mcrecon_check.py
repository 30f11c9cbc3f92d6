#!/usr/bin/env python3
#SBATCH --job-name=mcrecon-check
#SBATCH --output=mcrecon_check_%j.log
"""Checks a farm denoise (issue 19): every output frame of the plan exists and reads completely.

Same environment and arguments as mcrecon_array.sh (MCRECON, FRAMES; arguments: denoise and its
arguments). submit.sh queues it after the array (afterany, so a failed task still gets a report).
Exit 0 when every frame is there, 1 with the missing or unreadable frames listed.
"""
import json
import os
import re
import shutil
import subprocess
import sys


def output_pattern(args):
    for i, a in enumerate(args):
        if a in ("-o", "--output") and i + 1 < len(args):
            return args[i + 1]
        if a.startswith("--output="):
            return a[len("--output="):]
    sys.exit("mcrecon_check: no -o/--output among the denoise arguments")


def frame_path(pattern, frame):
    # The two pattern forms mcrecon denoise takes: shot_####.exr and shot_%04d.exr.
    if "#" in pattern:
        return re.sub(r"#+", lambda m: "%0*d" % (len(m.group()), frame), pattern, count=1)
    return re.sub(r"%0?\d*d", lambda m: m.group() % frame, pattern, count=1)


def main():
    args = sys.argv[1:]
    exe = shutil.which(os.environ.get("MCRECON", "mcrecon"))
    frames = os.environ.get("FRAMES")
    if not exe or not frames or not args:
        sys.exit("usage: MCRECON=... FRAMES=... mcrecon_check.py denoise IN -o OUT -f FILTER ...")
    # mcrecon's own frame list: a plan with one frame per chunk.
    plan = subprocess.run([exe, "plan", "--frames", frames, "--chunk", "1", "--json", "--", *args],
                          capture_output=True, text=True, check=True, timeout=300)
    wanted = [c["first"] for c in json.loads(plan.stdout)]
    pattern = output_pattern(args[1:])
    bad = []
    for f in wanted:
        path = frame_path(pattern, f)
        if not os.path.isfile(path):
            bad.append((f, path, "missing"))
            continue
        # mcrecon info reads every pixel: a truncated or corrupt EXR fails here.
        info = subprocess.run([exe, "info", path], capture_output=True, text=True, timeout=300)
        if info.returncode != 0:
            err = info.stderr.strip().splitlines()
            bad.append((f, path, "unreadable: " + (err[-1] if err else "exit %d" % info.returncode)))
    for f, path, why in bad:
        print("mcrecon_check: frame %d %s: %s" % (f, path, why))
    print("mcrecon_check: %d frames, %d ok, %d missing or unreadable"
          % (len(wanted), len(wanted) - len(bad), len(bad)))
    if bad:
        print("mcrecon_check: redo them by submitting the same command again (--resume keeps the "
              "good frames): frames %s" % ",".join(str(f) for f, _, _ in bad))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
