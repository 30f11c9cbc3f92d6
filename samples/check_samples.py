#!/usr/bin/python3
"""Check the rendered sample data against manifest.json and print quality tables.

    /usr/bin/python3 samples/check_samples.py [--data samples/data] [--png DIR]

Needs numpy and OpenImageIO (python3-openimageio: use Debian's /usr/bin/python3).
Checks: every file listed exists and has the expected channels; no NaN/Inf in any channel;
Combined is neither black nor blown out; the animation's Vector X/Y is non-zero on frames
after the first. Prints relMSE = mean((x - r)^2 / (r^2 + 0.01)) over Combined RGB of every
noisy level against its reference (per frame and averaged for the sequence), and the ratio
between successive levels (about 4 for 4x the samples). Half buffers (`halves`: two spp/2
renders with the level's seed and sample offsets 0 and spp/2) must average to the level's file
in every pass Cycles accumulates; Depth and Position, which Cycles writes on sample 0 only, must
be the level's in half 0 and unwritten (Depth 1e10, Position 0) in half 1.
A scene with `light_passes` must carry them in every noisy file, and they must sum to Combined:
(DiffDir+DiffInd)*DiffCol + (GlossDir+GlossInd)*GlossCol + (TransDir+TransInd)*TransCol + Emit
+ Env, up to half-float rounding.
Exit status 1 on any failure.
"""
import argparse
import json
import os
import sys

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
RGB = ["ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B"]
failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL: " + msg)


def read(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        fail(f"cannot open {path}: {oiio.geterror()}")
        return None, None
    spec = inp.spec()
    pix = inp.read_image("float")
    inp.close()
    return list(spec.channelnames), pix


def rel_mse(x, r):
    return float(np.mean((x - r) ** 2 / (r * r + 0.01)))


def combined(names, pix):
    return pix[..., [names.index(c) for c in RGB]]


# Scenes dark by design (their class is the exposure: a render at its physical brightness).
DIM = {"night": 0.005}


def check_file(path, passes):
    names, pix = read(path)
    if names is None:
        return None, None
    for p in passes:
        if not any(n.startswith(f"ViewLayer.{p}.") for n in names):
            fail(f"{path}: no '{p}' pass")
    bad = ~np.isfinite(pix)
    if bad.any():
        fail(f"{path}: {int(bad.sum())} NaN/Inf values in "
             f"{sorted({names[i] for i in np.nonzero(bad.any(axis=(0, 1)))[0]})}")
    rgb = combined(names, pix)
    m = float(rgb.mean())
    clipped = float((rgb.max(axis=2) > 1.0).mean())
    if m < DIM.get(os.path.basename(os.path.dirname(path)), 0.03):
        fail(f"{path}: too dark (mean {m:.4f})")
    if m > 2.0 or clipped > 0.25:
        fail(f"{path}: blown out (mean {m:.3f}, {clipped:.0%} of pixels above 1)")
    return names, pix


# Passes Cycles writes on the render's first sample (index 0) only: with sample_offset > 0 they
# stay at their clear value.
FIRST_SAMPLE_ONLY = {"Depth": 1e10, "Position": 0.0}


def check_halves(data, sc, spp, files):
    """Mean of the two half buffers against the level's own file, channel by channel."""
    names, full = read(os.path.join(data, sc["noisy"][spp]))
    halves = [read(os.path.join(data, f)) for f in files]
    if names is None or any(h[0] is None for h in halves):
        return
    if len(files) != 2 or any(h[0] != names for h in halves):
        fail(f"{sc['name']} {spp} spp halves: want 2 files with the level's channels, got {files}")
        return
    for f in files:
        check_file(os.path.join(data, f), sc["noisy_passes"])
    avg = (halves[0][1] + halves[1][1]) / 2
    worst, worst_rgb = 0.0, 0.0
    for i, c in enumerate(names):
        pas = c.split(".")[1]
        if pas in FIRST_SAMPLE_ONLY:
            if not (np.array_equal(halves[0][1][..., i], full[..., i])
                    and np.all(halves[1][1][..., i] == np.float32(FIRST_SAMPLE_ONLY[pas]))):
                fail(f"{sc['name']} halves: {c} is not the level's in half 0 and "
                     f"{FIRST_SAMPLE_ONLY[pas]:g} in half 1")
            continue
        d = np.abs(avg[..., i] - full[..., i])
        # Each file is rounded to half floats (colour passes): allow 2 half-float steps. A still's
        # motion is 0 but for Cycles' rounding at hair strands (up to 3e-5 px): 1e-4 px there.
        tol = 2.0 ** -9 * np.maximum(np.abs(full[..., i]), 2.0 ** -14) + (1e-4 if pas == "Vector" else 1e-6)
        if (d > tol).any():
            fail(f"{sc['name']} halves: mean of the halves differs from {sc['noisy'][spp]} in {c} "
                 f"by up to {float(d.max()):.3g} at {int((d > tol).sum())} pixels")
        worst = max(worst, float((d / np.maximum(np.abs(full[..., i]), 1e-3)).max()))
        if c in RGB:
            worst_rgb = max(worst_rgb, float(d.max()))
    print(f"{sc['name']}: mean of the {spp}-spp halves = {spp}-spp file up to {worst_rgb:.2g} "
          f"in Combined RGB (max relative difference over accumulated passes {worst:.2g}); "
          f"half 1 has no Depth/Position (Cycles writes them on sample 0 only)")


def light_sum(names, pix):
    """Blender's light passes recombined into the beauty, and the sum of the terms' magnitudes
    (what half-float rounding of the stored terms scales with)."""
    def g(p):
        return pix[..., [names.index(f"ViewLayer.{p}.{c}") for c in "RGB"]]
    terms = [(g(f"{k}Dir") + g(f"{k}Ind")) * g(f"{k}Col") for k in ("Diff", "Gloss", "Trans")]
    terms += [g("Emit"), g("Env")]
    scale = sum(np.abs(g(f"{k}Dir")) + np.abs(g(f"{k}Ind")) for k in ("Diff", "Gloss", "Trans"))
    return sum(terms), scale + np.abs(g("Emit")) + np.abs(g("Env"))


def check_light_passes(path, names, pix):
    """The light passes must sum to Combined; returns the worst relative difference."""
    got, scale = light_sum(names, pix)
    want = combined(names, pix)
    d = np.abs(got - want)
    # Every stored term and Combined are rounded to half (relative 2^-11); products and sums of
    # up to 9 such terms: allow 2^-8 of the magnitudes involved.
    tol = 2.0 ** -8 * (scale + np.abs(want)) + 1e-5
    if (d > tol).any():
        fail(f"{path}: light passes do not sum to Combined at {int((d > tol).any(axis=2).sum())} "
             f"pixels (up to {float(d.max()):.3g})")
    return float((d / np.maximum(np.abs(want), 1e-3)).max()), float(d.max())


def frame_paths(data, pattern, frames):
    return [(f, os.path.join(data, pattern.replace("####", f"{f:04d}")))
            for f in range(frames[0], frames[1] + 1)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.path.join(HERE, "data"))
    ap.add_argument("--png", default="", help="write sRGB previews of reference and 1/4 spp here")
    args = ap.parse_args()
    with open(os.path.join(args.data, "manifest.json")) as f:
        manifest = json.load(f)

    table = []  # (scene, spp, relMSE)
    total_bytes = 0
    for sc in manifest["scenes"]:
        name, seq = sc["name"], sc["kind"] == "sequence"
        if sc.get("split") not in ("tune", "report"):
            fail(f"{name}: split is {sc.get('split')!r}, want 'tune' or 'report'")
        print(f"{name}: split {sc.get('split')}, indirect clamp {sc['cycles']['clamp_indirect']:g}")
        frames = sc.get("frames", [1, 1])
        ref_pat = sc["reference"]
        refs = {}
        for f, path in (frame_paths(args.data, ref_pat, frames) if seq
                        else [(None, os.path.join(args.data, ref_pat))]):
            names, pix = check_file(path, sc["reference_passes"])
            total_bytes += os.path.getsize(path)
            if names is not None:
                refs[f] = combined(names, pix)
                m = refs[f].mean(axis=(0, 1))
                if f in (None, frames[0]):
                    print(f"{name}: reference mean RGB {m[0]:.3f} {m[1]:.3f} {m[2]:.3f}")
                if args.png and f in (None, frames[0]):
                    png(path, args.png)
        for spp, pat in sorted(sc["noisy"].items(), key=lambda kv: int(kv[0])):
            errs, vec, light = [], [], []
            for f, path in (frame_paths(args.data, pat, frames) if seq
                            else [(None, os.path.join(args.data, pat))]):
                names, pix = check_file(path, sc["noisy_passes"])
                total_bytes += os.path.getsize(path)
                if names is None:
                    continue
                if names[:4] != RGB + ["ViewLayer.Combined.A"]:
                    fail(f"{path}: unexpected channel order {names[:4]}")
                errs.append(rel_mse(combined(names, pix), refs[f]))
                if sc.get("light_passes"):
                    light.append(check_light_passes(path, names, pix))
                if seq:
                    vx = np.abs(pix[..., names.index("ViewLayer.Vector.X")]).mean()
                    vy = np.abs(pix[..., names.index("ViewLayer.Vector.Y")]).mean()
                    vec.append((f, vx, vy))
                    if f > frames[0] and (vx < 0.05 and vy < 0.05):
                        fail(f"{path}: Vector pass is (nearly) zero: |X| {vx:.4f} |Y| {vy:.4f}")
                if args.png and f in (None, frames[0]) and int(spp) <= 4:
                    png(path, args.png)
            table.append((name, int(spp), float(np.mean(errs)), len(errs)))
            if light:
                print(f"{name}: {spp}-spp light passes sum to Combined up to "
                      f"{max(v[1] for v in light):.3g} (relative {max(v[0] for v in light):.2g}) "
                      f"in {len(light)} file(s)")
            if spp in sc.get("halves", {}):
                for f in sc["halves"][spp]:
                    total_bytes += os.path.getsize(os.path.join(args.data, f))
                check_halves(args.data, sc, spp, sc["halves"][spp])
            if vec and spp == min(sc["noisy"], key=int):
                vx = np.array([v[1] for v in vec])
                vy = np.array([v[2] for v in vec])
                print(f"{name}: mean |Vector.X| per frame {vx.min():.2f}..{vx.max():.2f} px, "
                      f"|Vector.Y| {vy.min():.2f}..{vy.max():.2f} px (frames "
                      f"{vec[0][0]}..{vec[-1][0]})")

    print("\n| scene | spp | relMSE | ratio to next level |")
    print("|---|---:|---:|---:|")
    for i, (name, spp, e, n) in enumerate(table):
        nxt = table[i + 1] if i + 1 < len(table) and table[i + 1][0] == name else None
        ratio = f"{e / nxt[2]:.2f} (x{nxt[1] // spp} spp)" if nxt else ""
        frames_note = f" (mean of {n} frames)" if n > 1 else ""
        print(f"| {name} | {spp} | {e:.5f}{frames_note} | {ratio} |")
    print(f"\nchecked data: {total_bytes / 1e6:.1f} MB in the files listed by the manifest")
    if failures:
        print(f"{len(failures)} failure(s)")
        return 1
    print("all checks passed")
    return 0


def png(path, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    buf = oiio.ImageBuf(path)
    names = list(buf.spec().channelnames)
    rgb = oiio.ImageBufAlgo.channels(buf, tuple(names.index(c) for c in RGB))
    rgb = oiio.ImageBufAlgo.colorconvert(rgb, "linear", "sRGB")
    out = os.path.join(out_dir, os.path.splitext(os.path.basename(path))[0] + ".png")
    rgb.write(out, "uint8")


if __name__ == "__main__":
    sys.exit(main())
