"""A depth-of-field light field from Blender (issue 18): a thin lens sampled by pinhole renders.

The camera's depth of field is turned off and the camera is moved across the aperture (a K x K
grid of lens positions over the square [-1, 1]^2 in units of the aperture radius), each view with
a lens shift that keeps the focus plane where it was: pixel x of the view at lens point u then
sees along the thin lens's ray (x, u). Every view is rendered with all its samples through the
pixel centre (filter width 0.01 px), so a view's only noise is its shading's.

From the views it writes, for each l in --l (l x l samples per pixel, uniform jittered: one
random offset per pixel within the K/l x K/l views of each lens stratum):
  <scene>_lf_<l*l>spp.exr    the light field (deep EXR, README: the light-field convention):
                             lens coordinate (lf.y1 along image x, lf.y2 along image y down),
                             slopes s = -c from each sample's planar depth z,
                             c = R * f_px * (1/F - 1/z) pixels per unit of lens coordinate;
  <scene>_lf_<l*l>spp_flat.exr  the same samples as a flat image for the image-space filters:
                             colour = the samples' aperture-weighted mean (Gaussian, sigma 0.5,
                             what the light field's flat colour is), and their depth, normal and
                             albedo averaged with the same weights;
and <scene>_lf_ref.exr: every view, aperture-weighted (the converged image).

    blender -b --factory-startup --python-exit-code 1 --python lightfield_dof.py -- \\
        --scene dof_spheres --out DIR [--grid 24] [--view-spp 16] [--l 2 3 4] [--width 128] [--height 96]
"""
import argparse
import importlib
import json
import math
import os
import sys
import tempfile
import time

import bpy
import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402

SIGMA = 0.5  # Gaussian aperture over the lens square [-1, 1]^2 (the paper's 2A = 4 sigma)


def read_view(path, names):
    """Channels of a multilayer EXR as an (h, w, len(names)) float array."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        sys.exit(f"cannot read {path}: {oiio.geterror()}")
    spec = inp.spec()
    pix = inp.read_image(oiio.FLOAT)
    inp.close()
    idx = [list(spec.channelnames).index(n) for n in names]
    return pix[:, :, idx]


def render_views(scene, grid, view_spp, tmp):
    """Every lens position's view: colour, planar depth, normal, albedo."""
    cam = scene.camera
    d = cam.data
    lens_m = d.lens * 1e-3
    focus = d.dof.focus_distance
    radius = lens_m / (2.0 * d.dof.aperture_fstop)  # aperture radius, m
    d.dof.use_dof = False
    base = cam.matrix_world.copy()
    right, up = base.to_3x3().col[0].normalized(), base.to_3x3().col[1].normalized()
    sensor = d.sensor_width * 1e-3
    scene.cycles.samples = view_spp
    scene.cycles.filter_width = 0.01
    names = ["ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B", "ViewLayer.Depth.Z",
             "ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z", "ViewLayer.Denoising Albedo.R",
             "ViewLayer.Denoising Albedo.G", "ViewLayer.Denoising Albedo.B"]
    coords = (np.arange(grid) + 0.5) * 2.0 / grid - 1.0
    views = None
    t0 = time.time()
    for j, v in enumerate(coords):       # lens y2 (image down) = -camera up
        for i, u in enumerate(coords):   # lens y1 = camera right
            o_right, o_up = u * radius, -v * radius
            m = base.copy()
            m.translation = base.translation + right * o_right + up * o_up
            cam.matrix_world = m
            # Keep the focus plane: the frustum moves back by the camera's offset seen on the
            # focus plane, in units of the sensor width (Blender's shift).
            d.shift_x = -o_right * lens_m / (focus * sensor)
            d.shift_y = -o_up * lens_m / (focus * sensor)
            scene.cycles.seed = 1000 + j * grid + i
            path = os.path.join(tmp, "view.exr")
            scene.render.filepath = path
            bpy.ops.render.render(write_still=True)
            img = read_view(path, names)
            if views is None:
                views = np.zeros((grid, grid) + img.shape, np.float32)
            views[j, i] = img
            done = j * grid + i + 1
            print(f"lightfield_dof: view {done}/{grid * grid} ({time.time() - t0:.0f} s)", flush=True)
    cam.matrix_world = base
    d.shift_x = d.shift_y = 0.0
    width = scene.render.resolution_x
    f_px = d.lens / d.sensor_width * width
    return views, coords, radius * f_px, focus


def weights(coords):
    g = np.exp(-0.5 * (coords / SIGMA) ** 2)
    return np.outer(g, g)  # [y2, y1]


def write_flat(path, arrays):
    """A plain float EXR with named channels (colour R G B first)."""
    names, planes = [], []
    for prefix, arr, chans in arrays:
        for c, ch in enumerate(chans):
            names.append(f"{prefix}{ch}" if prefix else ch)
            planes.append(arr[..., c])
    data = np.stack(planes, axis=-1).astype(np.float32)
    h, w, n = data.shape
    spec = oiio.ImageSpec(w, h, n, oiio.FLOAT)
    spec.channelnames = tuple(names)
    spec.attribute("compression", "zip")
    tmp = path + ".tmp.exr"
    out = oiio.ImageOutput.create(tmp)
    if not out or not out.open(tmp, spec) or not out.write_image(data):
        sys.exit(f"cannot write {path}: {oiio.geterror()}")
    out.close()
    os.replace(tmp, path)


def write_lightfield(path, views, coords, c_scale, focus, l, rng):
    """l x l samples per pixel from the views, uniform jittered (one offset per pixel)."""
    grid = views.shape[0]
    h, w = views.shape[2], views.shape[3]
    step = grid // l
    jit = rng.integers(0, step, size=(h, w, 2))
    spp = l * l
    chans = ["R", "G", "B", "lf.y1", "lf.y2", "lf.smin", "lf.smax", "lf.e1x", "lf.e1y", "lf.e2x", "lf.e2y", "Z"]
    per = {c: np.zeros((h, w, spp), np.float32) for c in chans}
    feat = np.zeros((h, w, spp, 7), np.float32)  # depth, normal, albedo of each sample
    yy, xx = np.mgrid[0:h, 0:w]
    k = 0
    for b in range(l):
        for a in range(l):
            j = b * step + jit[..., 1]
            i = a * step + jit[..., 0]
            v = views[j, i, yy, xx]  # (h, w, 10)
            per["R"][..., k], per["G"][..., k], per["B"][..., k] = v[..., 0], v[..., 1], v[..., 2]
            per["lf.y1"][..., k] = coords[i]
            per["lf.y2"][..., k] = coords[j]
            z = np.maximum(v[..., 3], 1e-4)
            s = -c_scale * (1.0 / focus - 1.0 / z)
            per["lf.smin"][..., k] = s
            per["lf.smax"][..., k] = s
            feat[..., k, :] = v[..., 3:10]
            k += 1
    smin = per["lf.smin"].min(axis=2, keepdims=True)
    smax = per["lf.smax"].max(axis=2, keepdims=True)
    per["lf.smin"][:] = smin
    per["lf.smax"][:] = smax
    per["lf.e1x"][:] = 1.0
    per["lf.e2y"][:] = 1.0
    per["Z"][:] = feat[..., 0, 0:1]
    # Deep write: every pixel l*l samples.
    spec = oiio.ImageSpec(w, h, len(chans), oiio.FLOAT)
    spec.channelnames = tuple(chans)
    spec.deep = True
    spec.z_channel = chans.index("Z")
    spec.attribute("compression", "zips")
    spec.attribute("mcrecon:lightfield", "dof")
    spec.attribute("mcrecon:lf_l", float(l))
    spec.attribute("mcrecon:lf_y_range", 1.0)
    spec.attribute("mcrecon:lf_sigma_y", SIGMA)
    dd = oiio.DeepData()
    dd.init(spec)
    for p in range(w * h):
        dd.set_samples(p, spp)
    for ci, c in enumerate(chans):
        flat = per[c].reshape(w * h, spp)
        for p in range(w * h):
            row = flat[p]
            for s in range(spp):
                dd.set_deep_value(p, ci, s, float(row[s]))
    tmp = path + ".tmp.exr"
    out = oiio.ImageOutput.create(tmp)
    if not out or not out.open(tmp, spec) or not out.write_deep_image(dd):
        sys.exit(f"cannot write {path}: {oiio.geterror()}")
    out.close()
    os.replace(tmp, path)
    # The same samples, aperture-weighted, as a flat image with features.
    g = np.exp(-0.5 * (per["lf.y1"] / SIGMA) ** 2) * np.exp(-0.5 * (per["lf.y2"] / SIGMA) ** 2)
    g /= g.sum(axis=2, keepdims=True)
    colour = np.stack([(per[c] * g).sum(axis=2) for c in "RGB"], axis=-1)
    f = (feat * g[..., None]).sum(axis=2)
    return colour, f


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="lightfield_dof.py")
    p.add_argument("--scene", default="dof_spheres")
    p.add_argument("--out", required=True)
    p.add_argument("--grid", type=int, default=24, help="K: K x K lens positions (divisible by every l)")
    p.add_argument("--view-spp", type=int, default=16)
    p.add_argument("--l", type=int, nargs="+", default=[2, 3, 4])
    p.add_argument("--width", type=int, default=128)
    p.add_argument("--height", type=int, default=96)
    p.add_argument("--seed", type=int, default=18)
    a = p.parse_args(argv)
    for l in a.l:
        if a.grid % l:
            sys.exit(f"--grid {a.grid} is not divisible by l = {l}")
    mod = importlib.import_module(a.scene)
    scene = mod.build()
    vl = C.configure_render(scene, a.width, a.height)
    C.set_passes(vl, True)
    scene.render.image_settings.color_depth = "32"
    os.makedirs(a.out, exist_ok=True)
    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        views, coords, c_scale, focus = render_views(scene, a.grid, a.view_spp, tmp)
    render_s = time.time() - t0
    wts = weights(coords)
    wts /= wts.sum()
    ref = np.einsum("ji,jihwc->hwc", wts, views[..., 0:3])
    write_flat(os.path.join(a.out, f"{a.scene}_lf_ref.exr"), [("", ref, "RGB")])
    rng = np.random.default_rng(a.seed)
    for l in a.l:
        colour, f = write_lightfield(os.path.join(a.out, f"{a.scene}_lf_{l * l}spp.exr"), views, coords, c_scale,
                                     focus, l, rng)
        write_flat(os.path.join(a.out, f"{a.scene}_lf_{l * l}spp_flat.exr"),
                   [("", colour, "RGB"), ("Depth.", f[..., 0:1], "Z"), ("Normal.", f[..., 1:4], "XYZ"),
                    ("Albedo.", f[..., 4:7], "RGB")])
    print(json.dumps({"lightfield_dof": {"scene": a.scene, "grid": a.grid, "view_spp": a.view_spp,
                                         "render_s": round(render_s, 1), "coc_px_per_lens_unit_scale": c_scale,
                                         "focus_m": focus}}), flush=True)


if __name__ == "__main__":
    main()
