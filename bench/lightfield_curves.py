#!/usr/bin/env python3
"""Run time against error for the light-field filters (issue 18, points 1, 2 and 4).

For each generator scene (`mcrecon lightfield`), light fields at l = 1..L (spp = l*l) and one
reference; every filter (`sheared`, `aaf`, `sheared4d` up to --max-l-4d, and the unfiltered
estimate) is run through `mcrecon denoise --timings` and scored by `mcrecon compare` against the
reference. Then, per l in 2, 3, 4: the samples `aaf` needs to reach `sheared`'s relMSE
(interpolated in log-log between the measured spp), and `sheared` against `sheared4d` (relMSE
between the two and the speed ratio). With --blender DIR, the Blender depth-of-field light
field (samples/scenes/lightfield_dof.py) against the image-space filters at equal samples.

    bench/lightfield_curves.py --mcrecon build/bin/mcrecon --out DIR [--scenes soft_shadows dof gi soft_shadows_dof]
        [--max-l 8] [--max-l-4d 4] [--size 128] [--blender samples/data/lightfield]

Writes DIR/lightfield_curves.json and prints markdown tables. Times are the filter's own wall
time from --timings (not the file read and write), on whatever the machine is doing: run it on
an idle machine.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys

IMAGE_FILTERS = ["box", "gaussian", "bilateral", "atrous", "guided", "pwaf", "auto"]


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    return p.stdout + p.stderr


def filter_ms(text):
    m = re.search(r"filter ([0-9.]+) ms", text)
    return float(m.group(1)) if m else float("nan")


def relmse(mc, ref, img):
    return json.loads(run([mc, "compare", ref, img, "--json"]))["relmse"]


def denoise(mc, flt, src, out, sets=()):
    cmd = [mc, "denoise", "-f", flt, src, "-o", out, "--timings"]
    for s in sets:
        cmd += ["--set", s]
    return filter_ms(run(cmd))


def spp_for_error(curve, target):
    """The spp at which a decreasing error curve [(spp, err)] reaches target (log-log)."""
    pts = sorted(curve)
    for (s0, e0), (s1, e1) in zip(pts, pts[1:]):
        if e0 >= target >= e1 and e0 > 0 and e1 > 0:
            t = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(s0) + t * (math.log(s1) - math.log(s0)))
    if pts and target < pts[-1][1]:
        return None  # not reached within the measured range: more than the largest spp
    return pts[0][0] if pts else None


def scene_curves(a, scene):
    d = os.path.join(a.out, scene)
    os.makedirs(d, exist_ok=True)
    ref = os.path.join(d, "ref.exr")
    if not os.path.exists(ref):
        run([a.mcrecon, "lightfield", "--scene", scene, "--reference", "--width", str(a.size), "--height",
             str(a.size), "-o", ref])
    rows = []
    for l in range(1, a.max_l + 1):
        lf = os.path.join(d, f"lf_{l * l}spp.exr")
        if not os.path.exists(lf):
            run([a.mcrecon, "lightfield", "--scene", scene, "--spp", str(l * l), "--width", str(a.size), "--height",
                 str(a.size), "-o", lf])
        row = {"scene": scene, "l": l, "spp": l * l, "input": relmse(a.mcrecon, ref, lf)}
        for flt in ["sheared", "aaf"] + (["sheared4d"] if l <= a.max_l_4d else []):
            out = os.path.join(d, f"{flt}_{l * l}spp.exr")
            row[flt + "_ms"] = denoise(a.mcrecon, flt, lf, out)
            row[flt] = relmse(a.mcrecon, ref, out)
            if flt == "sheared4d":
                row["sheared_vs_4d"] = relmse(a.mcrecon, out, os.path.join(d, f"sheared_{l * l}spp.exr"))
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def sample_ratios(rows):
    aaf = [(r["spp"], r["aaf"]) for r in rows]
    out = []
    for r in rows:
        if r["l"] in (2, 3, 4):
            need = spp_for_error(aaf, r["sheared"])
            out.append({"scene": r["scene"], "l": r["l"], "spp": r["spp"], "sheared": r["sheared"],
                        "aaf_spp_for_equal_error": need, "ratio": need / r["spp"] if need else None})
    return out


def blender_dof(a):
    d = a.blender
    ref = os.path.join(d, "dof_spheres_lf_ref.exr")
    rows = []
    for l in (2, 3, 4):
        n = l * l
        lf, flat = os.path.join(d, f"dof_spheres_lf_{n}spp.exr"), os.path.join(d, f"dof_spheres_lf_{n}spp_flat.exr")
        row = {"spp": n, "input": relmse(a.mcrecon, ref, flat)}
        for flt in ["sheared", "aaf"]:
            out = os.path.join(a.out, f"blender_{flt}_{n}.exr")
            row[flt + "_ms"] = denoise(a.mcrecon, flt, lf, out)
            row[flt] = relmse(a.mcrecon, ref, out)
        for flt in IMAGE_FILTERS:
            out = os.path.join(a.out, f"blender_{flt}_{n}.exr")
            row[flt + "_ms"] = denoise(a.mcrecon, flt, flat, out)
            row[flt] = relmse(a.mcrecon, ref, out)
        best = min(IMAGE_FILTERS, key=lambda f: row[f])
        row["best_image_filter"] = best
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--mcrecon", default="build/bin/mcrecon")
    p.add_argument("--out", required=True)
    p.add_argument("--scenes", nargs="+", default=["soft_shadows", "dof", "gi", "soft_shadows_dof"])
    p.add_argument("--max-l", type=int, default=8)
    p.add_argument("--max-l-4d", type=int, default=4)
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--blender", help="folder with the Blender dof light fields (samples/data/lightfield)")
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    result = {"scenes": {}, "ratios": [], "blender": []}
    for s in a.scenes:
        rows = scene_curves(a, s)
        result["scenes"][s] = rows
        result["ratios"] += sample_ratios(rows)
    if a.blender:
        result["blender"] = blender_dof(a)
    with open(os.path.join(a.out, "lightfield_curves.json"), "w") as f:
        json.dump(result, f, indent=1)
    for s, rows in result["scenes"].items():
        print(f"\n### {s}: relMSE (filter ms)\n\n| spp | input | sheared | aaf | sheared4d | sheared vs 4d |\n|---|---:|---:|---:|---:|---:|")
        for r in rows:
            f4 = f"{r['sheared4d']:.5f} ({r['sheared4d_ms']:.0f})" if "sheared4d" in r else ""
            v4 = f"{r['sheared_vs_4d']:.5f}" if "sheared_vs_4d" in r else ""
            print(f"| {r['spp']} | {r['input']:.5f} | {r['sheared']:.5f} ({r['sheared_ms']:.0f}) | "
                  f"{r['aaf']:.5f} ({r['aaf_ms']:.0f}) | {f4} | {v4} |")
    print("\n### samples aaf needs for sheared's error\n\n| scene | l | spp | sheared relMSE | aaf spp | ratio |\n|---|---:|---:|---:|---:|---:|")
    for r in result["ratios"]:
        need = f"{r['aaf_spp_for_equal_error']:.1f}" if r["aaf_spp_for_equal_error"] else "> max"
        ratio = f"{r['ratio']:.1f}x" if r["ratio"] else "> max"
        print(f"| {r['scene']} | {r['l']} | {r['spp']} | {r['sheared']:.5f} | {need} | {ratio} |")
    if result["blender"]:
        print("\n### Blender dof light field (dof_spheres): relMSE\n\n| spp | input | sheared | aaf | best image filter |\n|---|---:|---:|---:|---|")
        for r in result["blender"]:
            b = r["best_image_filter"]
            print(f"| {r['spp']} | {r['input']:.5f} | {r['sheared']:.5f} | {r['aaf']:.5f} | {b} {r[b]:.5f} |")


if __name__ == "__main__":
    main()
