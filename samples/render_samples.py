#!/usr/bin/env python3
"""Render mcrecon's sample scenes with Blender (Cycles, CPU) and write samples/data/manifest.json.

    python3 samples/render_samples.py                       # everything (~35 min on 2 idle cores)
    python3 samples/render_samples.py --scenes room,dof     # some scenes (manifest entries merged)
    python3 samples/render_samples.py --spp 1,4 --ref-spp 256 --out /tmp/quick   # quick look

One Blender process per scene builds the scene once and renders every spp level (and every frame
of the animation). A progress line is printed per file written; Blender's own output goes to
samples/render_tmp/logs/<scene>.log. Only the standard library is needed here.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE_DIR = os.path.join(HERE, "scenes")

SCENES = {
    "room": ("still", "Closed Cornell-box-like room lit almost only indirectly (lamp aimed at the "
                      "ceiling from behind a hanging panel, small warm window): high noise."),
    "glossy": ("still", "Checker floor and brick wall with metal spheres of increasing roughness, "
                        "noise/brick/wave-textured objects and a gold torus under two area lights."),
    "dof": ("still", "Shallow depth of field (85 mm f/1.2, focus 4 m): sharp textured Suzanne, "
                     "blurred foreground objects and background columns, wall and bokeh bulbs."),
    "anim": ("sequence", "16-frame keyframed camera truck/pan through a textured room with a table, "
                         "shelf and spheres; a spinning cube adds object motion."),
    "sunlit": ("still", "Attic lit by the sun through a narrow window slit (hard patch on the floor) "
                        "and a weak sky; brick and wave-striped walls, plank floor, polished gold "
                        "sphere in the sun (tiny, very bright highlight), rough steel ring, clay "
                        "Suzanne."),
    "showroom": ("still", "Showroom under a procedural sky and a sun: car paint with flakes, "
                          "brushed (anisotropic) steel, walnut, and glass spheres whose caustics "
                          "are rare bright samples (indirect clamp off: fireflies)."),
    "wall": ("still", "A flat plastered brick wall filling the frame, seen straight on by an "
                      "orthographic camera (constant Normal and Depth passes), grazing area light "
                      "and the soft shadow of a pole outside the view; no depth of field."),
    "metal": ("sequence", "16-frame keyframed camera orbit (3 degrees per frame) around a polished "
                          "gold sphere that mirrors a small, strong sun (the reflection slides "
                          "over it), a brushed-steel torus and a glass ball on a glossy checkered "
                          "floor before a low brick wall; indirect clamp off (fireflies); the "
                          "noisy frames carry Blender's light passes."),
    "chrome": ("sequence", "16-frame keyframed dolly (left and in, panning along) past a chrome "
                           "tap, kettle and bevelled toaster, a brushed-steel tray, a glass and a "
                           "mug on a wooden counter before glossy tiles, lit by one small, strong "
                           "point lamp (its highlights slide over the chrome) and a dim world; "
                           "indirect clamp off; with the light passes; held out: never used to "
                           "choose settings."),
    "orbit": ("sequence", "16-frame keyframed camera orbit (2.5 degrees per frame) around blue car "
                          "paint, a brushed-steel column, a polished gold torus, a walnut block "
                          "and a glass sphere on a dark glossy turntable, lit by an outdoor HDRI "
                          "(Blender's courtyard studio light) and a strong sun; indirect clamp "
                          "off; with the light passes; held out: never used to choose settings."),
    "fog": ("still", "Hazy warehouse bay inside homogeneous fog: sun shafts through four gaps in "
                     "a brick wall, a spot lamp's visible cone on a checkered floor, cyan and "
                     "magenta neon tubes, crates, a metal drum, a glossy ball (in-scattered light "
                     "that no feature pass describes); held out: never used to choose settings."),
    "fence": ("still", "A wire mesh fence (wires about half a pixel wide) before a cut-out hedge "
                       "(Voronoi leaves over a Transparent BSDF) and a stucco wall, under a sun "
                       "and a sky: every feature pass is aliased at the wires and leaf edges; "
                       "held out: never used to choose settings."),
    "night": ("still", "A street corner at night at its physical brightness (mean luminance about "
                       "0.02, no film exposure): a sodium street lamp, a lit shop window, a wet "
                       "puddle, a metal bin and a glossy box-car under a faint moonlit sky; held "
                       "out: never used to choose settings."),
    "studio": ("still", "A photo table: a furry ball (particle hair far thinner than a pixel), a "
                        "subsurface wax candle with a small bright flame, a screen showing an "
                        "emissive wave pattern and two leaves lit from behind (translucent); a "
                        "soft key light, a warm rim spot and a dim world; held out: never used "
                        "to choose settings."),
    "product": ("still", "A product shot on a transparent background (Film > Transparent) with a "
                         "shadow-catcher floor: a glass perfume bottle with a gold cap, a glazed "
                         "vase, a brushed-steel cube and a matte box under a soft key light, a rim "
                         "light and a sky only the glass and metal show; the soft shadows live in "
                         "the alpha; held out: never used to choose settings."),
    "cutout": ("still", "studio's objects as a cut-out on a transparent background (Film > "
                        "Transparent, no table or wall): the fur's fringe of sub-pixel hair, the "
                        "back-lit leaves' edges and the flame are partial coverage against alpha "
                        "0; held out: never used to choose settings."),
    "jewel": ("still", "Polished silver, a gold ring, chrome bearing balls, a cut-glass prism and a "
                       "brushed spoon under a sun on a transparent background with a shadow "
                       "catcher: at 64 spp the sun's sub-pixel mirror images are most of the "
                       "error; a tune scene of that class."),
}
ORDER = ["room", "glossy", "dof", "anim", "sunlit", "showroom", "wall", "metal", "chrome", "orbit", "fog", "fence",
         "night", "studio",
         "product", "cutout", "jewel"]
# Parameters are chosen on the "tune" scenes and reported on the "report" scenes.
SPLIT = {"room": "tune", "glossy": "tune", "dof": "report", "anim": "report",
         "sunlit": "report", "showroom": "report", "wall": "report", "metal": "report",
         "chrome": "report", "orbit": "report", "fog": "report", "fence": "report",
         "night": "report", "studio": "report", "product": "report",
         "cutout": "report", "jewel": "tune"}
# Noisy levels also rendered as two half buffers (same seed, sample offsets 0 and spp/2).
HALVES = {"sunlit": [16], "showroom": [16], "wall": [16], "fog": [16], "fence": [16], "night": [16], "studio": [16],
          "cutout": [16]}

# Channel groups Blender writes (view layer "ViewLayer", compositing off).
NOISY_PASSES = ["Combined", "Denoising Albedo", "Denoising Depth", "Denoising Normal", "Depth",
                "DiffCol", "GlossCol", "Normal", "Position", "Vector"]


def int_list(text):
    return [int(t) for t in text.split(",") if t.strip()]


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenes", default=",".join(ORDER),
                   help="comma-separated subset of " + ",".join(ORDER))
    p.add_argument("--out", default=os.path.join(HERE, "data"), help="data folder")
    p.add_argument("--spp", type=int_list, default=[1, 4, 16, 64], help="noisy spp of the stills")
    p.add_argument("--ref-spp", type=int, default=2048, help="reference spp of the stills")
    p.add_argument("--anim-spp", type=int_list, default=[1], help="noisy spp of the animation")
    p.add_argument("--anim-ref-spp", type=int, default=128, help="reference spp per frame")
    p.add_argument("--frames", default="1-16", help="animation frame range")
    p.add_argument("--still-size", default="256x192", help="WxH of the stills")
    p.add_argument("--anim-size", default="320x180", help="WxH of the animation")
    p.add_argument("--metal-size", default="256x144", help="WxH of the metal sequence")
    p.add_argument("--metal-ref-spp", type=int, default=512,
                   help="reference spp per frame of the metal sequence")
    p.add_argument("--chrome-size", default="192x108", help="WxH of the chrome sequence")
    p.add_argument("--chrome-ref-spp", type=int, default=512,
                   help="reference spp per frame of the chrome sequence")
    p.add_argument("--orbit-size", default="192x108", help="WxH of the orbit sequence")
    p.add_argument("--orbit-ref-spp", type=int, default=512,
                   help="reference spp per frame of the orbit sequence")
    p.add_argument("--threads", type=int, default=0, help="Cycles threads (0 = all cores)")
    p.add_argument("--blender", default=os.environ.get("BLENDER", "blender"))
    return p.parse_args()


def blender_version(blender):
    out = subprocess.run([blender, "--version"], capture_output=True, text=True).stdout
    first = out.strip().splitlines()[0] if out.strip() else "unknown"
    return first.replace("Blender", "").strip()


def seq_settings(args, name):
    """(WxH, reference spp) of a sequence: each has its own options."""
    if name == "metal":
        return args.metal_size, args.metal_ref_spp
    if name == "chrome":
        return args.chrome_size, args.chrome_ref_spp
    if name == "orbit":
        return args.orbit_size, args.orbit_ref_spp
    return args.anim_size, args.anim_ref_spp


def run_scene(args, name, counter, total):
    kind, _ = SCENES[name]
    seq = kind == "sequence"
    size, ref = seq_settings(args, name) if seq else (args.still_size, args.ref_spp)
    w, h = (int(v) for v in size.lower().split("x"))
    spp = args.anim_spp if seq else args.spp
    out_dir = os.path.join(args.out, name)
    os.makedirs(out_dir, exist_ok=True)
    cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", os.path.join(SCENE_DIR, f"{name}.py"), "--",
           "--out", out_dir, "--spp", ",".join(map(str, spp)), "--ref-spp", str(ref),
           "--width", str(w), "--height", str(h), "--threads", str(args.threads)]
    if seq:
        cmd += ["--frames", args.frames]
    halves = [h for h in HALVES.get(name, []) if h in spp]
    if halves:
        cmd += ["--halves", ",".join(map(str, halves))]
    log_dir = os.path.join(HERE, "render_tmp", "logs")
    os.makedirs(log_dir, exist_ok=True)
    log_path = os.path.join(log_dir, f"{name}.log")
    records, info = [], None
    t0 = time.perf_counter()
    with open(log_path, "w") as log:
        log.write(" ".join(cmd) + "\n")
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                bufsize=1)
        for line in proc.stdout:
            log.write(line)
            if line.startswith("MCRECON_FILE "):
                rec = json.loads(line[len("MCRECON_FILE "):])
                records.append(rec)
                counter[0] += 1
                what = rec["kind"] if rec["kind"] != "half" else f"half {rec['half']} of {rec['of_spp']}"
                frame = f" frame {rec['frame']:2d}" if rec["frame"] is not None else ""
                print(f"[{counter[0]}/{total}] {name} {rec['spp']} spp ({what}){frame} ... "
                      f"{rec['seconds']:.1f} s", flush=True)
            elif line.startswith("MCRECON_INFO "):
                info = json.loads(line[len("MCRECON_INFO "):])
        rc = proc.wait()
    wall = time.perf_counter() - t0
    if rc != 0 or info is None:
        with open(log_path) as f:
            tail = f.readlines()[-30:]
        sys.stderr.write("".join(tail))
        sys.exit(f"render_samples: Blender failed on '{name}' (exit {rc}); log: {log_path}")
    return records, info, wall


def manifest_entry(name, records, info, wall, out_root):
    kind, desc = SCENES[name]
    seq = kind == "sequence"
    noisy = sorted({r["spp"] for r in records if r["kind"] == "noisy"})
    refs = [r for r in records if r["kind"] == "ref"]
    halves = sorted((r for r in records if r["kind"] == "half"),
                    key=lambda r: (r["of_spp"], r["half"]))

    def rel(fname):
        return f"{name}/{fname}"

    def pattern(spp_or_ref):
        stem = f"{name}_{spp_or_ref}spp" if spp_or_ref != "ref" else f"{name}_ref"
        return rel(f"{stem}_####.exr") if seq else rel(f"{stem}.exr")

    def size(rec):
        return os.path.getsize(os.path.join(out_root, name, rec["file"]))

    def per_key(field):
        res = {}
        for key in [*noisy, "ref"]:
            recs = [r for r in records if (r["kind"] == "ref" if key == "ref"
                                           else r["kind"] == "noisy" and r["spp"] == key)]
            if not recs:
                continue
            vals = [field(r) for r in sorted(recs, key=lambda r: r["frame"] or 0)]
            res[str(key)] = vals if seq else vals[0]
        return res

    e = {"name": name, "kind": kind, "description": desc, "split": SPLIT[name],
         "width": info["width"], "height": info["height"]}
    if seq:
        e["frames"] = info["frames"]
        e["fps"] = info["fps"]
    e["noisy"] = {str(s): pattern(s) for s in noisy}
    light = info.get("light_passes", [])
    # Blender writes the passes in alphabetical order; DiffCol and GlossCol are in both lists.
    e["noisy_passes"] = sorted(set(NOISY_PASSES) | set(light)) if light else NOISY_PASSES
    if light:
        e["light_passes"] = light
    if halves:
        e["halves"] = {str(s): [rel(r["file"]) for r in halves if r["of_spp"] == s]
                       for s in sorted({r["of_spp"] for r in halves})}
    if refs:
        e["reference"] = pattern("ref")
        e["reference_spp"] = refs[0]["spp"]
        e["reference_passes"] = NOISY_PASSES if refs[0]["all_passes"] else ["Combined"]
    e["render_seconds"] = per_key(lambda r: r["seconds"])
    e["blender_wall_seconds"] = round(wall, 1)
    e["seeds"] = per_key(lambda r: r["seed"])
    e["file_bytes"] = per_key(size)
    if halves:
        e["halves_render_seconds"] = {r["file"]: r["seconds"] for r in halves}
        e["halves_file_bytes"] = {r["file"]: size(r) for r in halves}
        e["halves_sample_offsets"] = {r["file"]: r["sample_offset"] for r in halves}
    e["camera"] = info["camera"]
    e["blender_version"] = info["blender_version"]
    e["cycles"] = info["cycles"]
    return e


def dump_json(obj):
    """Indented JSON with lists of numbers kept on one line."""
    text = json.dumps(obj, indent=1)
    return re.sub(r"\[\s*([-0-9.eE,\s]*?)\s*\]",
                  lambda m: "[" + ", ".join(v.strip() for v in m.group(1).split(",")) + "]", text)


def main():
    args = parse_args()
    names = [n for n in args.scenes.split(",") if n]
    for n in names:
        if n not in SCENES:
            sys.exit(f"render_samples: unknown scene '{n}' (have {', '.join(ORDER)})")
    names = [n for n in ORDER if n in names]
    f0, _, f1 = args.frames.partition("-")
    nframes = int(f1 or f0) - int(f0) + 1
    total = 0
    for n in names:
        if SCENES[n][0] == "sequence":
            total += nframes * (len(args.anim_spp) + (seq_settings(args, n)[1] > 0))
        else:
            total += len(args.spp) + (args.ref_spp > 0) + \
                2 * len([h for h in HALVES.get(n, []) if h in args.spp])
    os.makedirs(args.out, exist_ok=True)
    man_path = os.path.join(args.out, "manifest.json")
    manifest = {"scenes": []}
    if os.path.isfile(man_path):
        with open(man_path) as f:
            manifest = json.load(f)
    print(f"render_samples: {total} renders of {', '.join(names)} with Blender "
          f"{blender_version(args.blender)} into {args.out}", flush=True)
    counter = [0]
    t_all = time.perf_counter()
    for n in names:
        records, info, wall = run_scene(args, n, counter, total)
        entry = manifest_entry(n, records, info, wall, args.out)
        scenes = {s["name"]: s for s in manifest.get("scenes", [])}
        scenes[n] = entry
        for s in scenes.values():  # entries written before the split existed
            s["split"] = SPLIT.get(s["name"], s.get("split", "report"))
        manifest["scenes"] = [scenes[k] for k in ORDER if k in scenes] + \
            [v for k, v in scenes.items() if k not in ORDER]
        manifest["generator"] = "samples/render_samples.py"
        manifest["blender_version"] = info["blender_version"]
        manifest["view_layer"] = "ViewLayer"
        manifest["format"] = ("OpenEXR multilayer, ZIP, half colour passes / float geometry "
                              "passes, linear scene-referred, channels 'ViewLayer.<Pass>.<C>'")
        with open(man_path, "w") as f:
            f.write(dump_json(manifest) + "\n")
        print(f"  {n}: done in {wall:.1f} s (Blender process wall time)", flush=True)
    print(f"render_samples: {counter[0]} files in {time.perf_counter() - t_all:.1f} s; "
          f"manifest: {man_path}", flush=True)


if __name__ == "__main__":
    main()
