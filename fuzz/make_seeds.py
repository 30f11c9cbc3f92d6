"""Seed corpora of the fuzz targets, written by OpenImageIO (no binaries in the repository).

    /usr/bin/python3 fuzz/make_seeds.py OUT_DIR

writes OUT_DIR/<target>/<seed> for every target of fuzz/CMakeLists.txt: small EXRs (every one
under 20 KB: Blender-like multilayer, multi-part, tiled, each compression, half and float,
deep scanline and deep tiled with 0, 1 and several samples per pixel), parameter and plugin
name texts, and filter-fuzzer inputs. Deterministic: the same files every run.
"""
import os
import random
import sys

import numpy as np
import OpenImageIO as oiio

COMPRESSIONS = ["none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"]
MAX_SEED_BYTES = 20 * 1024
FIXED_TIME = "2026:01:01 00:00:00"  # else OpenImageIO writes the current time


def blender_layer(layer):
    p = layer + "."
    return [p + "Combined.R", p + "Combined.G", p + "Combined.B", p + "Combined.A",
            p + "Denoising Albedo.R", p + "Denoising Albedo.G", p + "Denoising Albedo.B",
            p + "Normal.X", p + "Normal.Y", p + "Normal.Z",
            p + "Position.X", p + "Position.Y", p + "Position.Z", p + "Depth.Z",
            p + "Vector.X", p + "Vector.Y", p + "Vector.Z", p + "Vector.W",
            p + "Denoising Normal.X", p + "Denoising Normal.Y", p + "Denoising Normal.Z",
            p + "Denoising Depth.Z"]


def pixels(rng, w, h, c):
    return rng.uniform(0.0, 1.0, size=(h, w, c)).astype(np.float32)


def spec_for(w, h, names, fmt="float", compression="zip", tile=None):
    spec = oiio.ImageSpec(w, h, len(names), fmt)
    spec.channelnames = tuple(names)
    spec.attribute("compression", compression)
    spec.attribute("DateTime", FIXED_TIME)
    if tile:
        spec.tile_width, spec.tile_height = tile, tile
    return spec


def write(path, spec, data):
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec) or not out.write_image(data) or not out.close():
        raise RuntimeError("writing %s failed: %s" % (path, oiio.geterror()))


def write_parts(path, parts):
    """parts: list of (spec, data); one multi-part EXR."""
    out = oiio.ImageOutput.create(path)
    specs = [s for s, _ in parts]
    if out is None or not out.open(path, specs):
        raise RuntimeError("opening %s failed: %s" % (path, oiio.geterror()))
    for i, (spec, data) in enumerate(parts):
        if i and not out.open(path, spec, "AppendSubimage"):
            raise RuntimeError("part %d of %s: %s" % (i, path, out.geterror()))
        if not out.write_image(data):
            raise RuntimeError("part %d of %s: %s" % (i, path, out.geterror()))
    out.close()


def write_deep(path, w, h, counts, tile=None, compression="zips", rng=None, per_sample=False):
    """per_sample: the sweep's convention (README): no alpha, R G B Z dx dy, camera attributes."""
    names = ["R", "G", "B", "Z", "dx", "dy"] if per_sample else ["R", "G", "B", "A", "Z"]
    spec = oiio.ImageSpec(w, h, len(names), "float")
    spec.channelnames = tuple(names)
    if per_sample:
        spec.z_channel = 3
        for k, v in (("lens_mm", 50.0), ("fstop", 0.2), ("focus_distance", 3.0), ("sensor_width_mm", 36.0)):
            spec.attribute("mcrecon:" + k, v)
    else:
        spec.alpha_channel, spec.z_channel = 3, 4
    spec.deep = True
    spec.attribute("compression", compression)
    spec.attribute("DateTime", FIXED_TIME)
    if tile:
        spec.tile_width, spec.tile_height = tile, tile
    dd = oiio.DeepData()
    dd.init(spec)
    for p in range(w * h):
        n = counts[p % len(counts)]
        dd.set_samples(p, n)
        for s in range(n):
            for c in range(len(names)):
                v = 1.0 + s if names[c] == "Z" else float(rng.uniform(0.0, 1.0))
                dd.set_deep_value(p, c, s, v)
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec) or not out.write_deep_image(dd) or not out.close():
        raise RuntimeError("writing %s failed: %s" % (path, oiio.geterror()))


def flat_seeds(d, rng):
    names = blender_layer("ViewLayer")
    for comp in COMPRESSIONS:  # Blender-like multilayer, every compression, half
        write(os.path.join(d, "blender_%s_half.exr" % comp), spec_for(6, 5, names, "half", comp),
              pixels(rng, 6, 5, len(names)))
    write(os.path.join(d, "blender_zip_float.exr"), spec_for(6, 5, names, "float", "zip"),
          pixels(rng, 6, 5, len(names)))
    two = blender_layer("ViewLayer") + blender_layer("Other")
    write(os.path.join(d, "two_layers.exr"), spec_for(4, 3, two, "half", "zips"), pixels(rng, 4, 3, len(two)))
    rgba = ["R", "G", "B", "A"]
    for comp in ("none", "zip", "piz"):
        write(os.path.join(d, "tiled_%s.exr" % comp), spec_for(9, 7, rgba, "half", comp, tile=4),
              pixels(rng, 9, 7, 4))
    write(os.path.join(d, "tiled_float.exr"), spec_for(5, 5, ["R", "G", "B"], "float", "zip", tile=2),
          pixels(rng, 5, 5, 3))
    write(os.path.join(d, "rgb_1x1.exr"), spec_for(1, 1, ["R", "G", "B"], "float", "none"), pixels(rng, 1, 1, 3))
    loose = ["R", "G", "B", "A", "albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z", "Z"]
    write(os.path.join(d, "loose_passes.exr"), spec_for(5, 4, loose, "half", "zip"), pixels(rng, 5, 4, len(loose)))
    # Multi-part: colour in one part, features in another (as some renderers write).
    c_spec = spec_for(4, 4, ["R", "G", "B", "A"], "half", "zip")
    c_spec.attribute("name", "rgba")
    f_names = ["normal.X", "normal.Y", "normal.Z", "depth.Z"]
    f_spec = spec_for(4, 4, f_names, "float", "zips")
    f_spec.attribute("name", "features")
    write_parts(os.path.join(d, "multipart.exr"),
                [(c_spec, pixels(rng, 4, 4, 4)), (f_spec, pixels(rng, 4, 4, 4))])
    # A data window that is not the display window (crop / overscan).
    cropped = spec_for(4, 3, ["R", "G", "B"], "half", "zip")
    cropped.x, cropped.y = 2, 1
    cropped.full_x, cropped.full_y, cropped.full_width, cropped.full_height = 0, 0, 8, 6
    write(os.path.join(d, "data_window.exr"), cropped, pixels(rng, 4, 3, 3))


def deep_seeds(d, rng):
    for name, counts in (("zero", [0]), ("one", [1]), ("several", [0, 1, 3, 5])):
        write_deep(os.path.join(d, "deep_scan_%s.exr" % name), 4, 3, counts, rng=rng)
        write_deep(os.path.join(d, "deep_tiled_%s.exr" % name), 5, 4, counts, tile=2, rng=rng)
    write_deep(os.path.join(d, "deep_scan_none.exr"), 3, 3, [2], compression="none", rng=rng)
    write_deep(os.path.join(d, "deep_scan_rle.exr"), 3, 3, [1, 2], compression="rle", rng=rng)
    write_deep(os.path.join(d, "deep_per_sample.exr"), 4, 3, [0, 1, 4], rng=rng, per_sample=True)


# First byte: the filter (index into filter_names(): box guided gaussian bilateral atrous pwaf
# bmfr); '@' lines name a table entry by their next byte.
PARAM_SEEDS = {
    "box_radius": b"\x00radius=3\nclamp=10\nholes=auto",
    "guided": b"\x01guide=normal_depth\nradius=4\nepsilon=0.01\n@\x05 1e-3",
    "gaussian": b"\x02sigma=1.5\ndemodulate=true\nalbedo_floor=0.02",
    "bilateral": b"\x03radius=3\norder=1\ncolour_weight=noise\nuse_normal=on\nnormal_sigma=0.2",
    "atrous": b"\x04iterations=3\nkernel_size=5\ncolour_sigma_decay=0.5",
    "pwaf": b"\x05min_radius=2\nmax_radius=4\nadaptive=false\nfirefly_k=3",
    "bmfr": b"\x06features=with_albedo\nblock_size=16\ntaa=0\nseed=7",
    "foveated": b"\x00foveated=yes\ngaze_x=0.25\ninner_radius=0.1\nouter_radius=0.2",
    "frames": b"\x00render_####.exr\n1-16\nshot_%04d.exr\n7\n-3--1",
    "bad": b"\x03radius=abc\n=1\nradius\nsigma=1e999\nradius=5.5\n@\x00nan",
}

PLUGIN_SEEDS = {
    "query": b"\x00render.exr.mcrecon?filter=box&radius=3",
    "roles": b"\x00r.exr.mcrecon?filter=bilateral&layer=ViewLayer&normal=n.exr&accumulate=1",
    "output": b"\x01den.exr.mcrecon?filter=atrous&keep_passes=true&compression=piz",
    "suffix": b"\x02x.exr",
    "temp": b"\x00o_0001.963d536f.temp.exr.mcrecon?filter=bmfr&taa=0",
    "bad": b"\x00r.exr.mcrecon?filter=box&&radius",
}


def filter_seeds(d):
    r = random.Random(13)
    for i in range(7):  # one per filter: every pass present, default-ish parameters
        head = bytes([i, 8, 8, 0xff, 0xff, 0, 1, 0])
        body = bytes(r.randrange(256) for _ in range(64)) + bytes(range(8, 16)) * 2  # the special values
        with open(os.path.join(d, "filter_%d" % i), "wb") as f:
            f.write(head + body)
    with open(os.path.join(d, "tiny"), "wb") as f:
        f.write(bytes([0, 1, 1, 0, 0, 0, 0, 0, 10, 0]))


def main():
    out = sys.argv[1]
    rng = np.random.default_rng(13)
    dirs = {t: os.path.join(out, t) for t in ("read_frame", "read_deep", "params", "plugin_request", "filters")}
    for d in dirs.values():
        os.makedirs(d, exist_ok=True)
    flat_seeds(dirs["read_frame"], rng)
    deep_seeds(dirs["read_deep"], rng)
    for target, seeds in (("params", PARAM_SEEDS), ("plugin_request", PLUGIN_SEEDS)):
        for name, text in seeds.items():
            with open(os.path.join(dirs[target], name), "wb") as f:
                f.write(text)
    filter_seeds(dirs["filters"])
    for d in dirs.values():
        for name in os.listdir(d):
            size = os.path.getsize(os.path.join(d, name))
            if size > MAX_SEED_BYTES:
                raise SystemExit("make_seeds: %s/%s is %d bytes (limit %d)" % (d, name, size, MAX_SEED_BYTES))


if __name__ == "__main__":
    main()
