"""A small synthetic Blender-style multilayer EXR with every light pass, for the tests of
components=light_passes (CLI, Python module, plugin).

The light passes are drawn at random (noisy light, smooth colour passes) and Combined is built
from them by Blender's identity, so the file is what Blender writes:
  Combined = (DiffDir+DiffInd)*DiffCol + (GlossDir+GlossInd)*GlossCol
           + (TransDir+TransInd)*TransCol + Emit + Env
"""
import numpy as np

import mcrecon_testutil as tu

LAYER = "ViewLayer"
COMPONENTS = [("Diffuse", "Diff"), ("Glossy", "Gloss"), ("Transmission", "Trans")]
PASSES = ["DiffDir", "DiffInd", "DiffCol", "GlossDir", "GlossInd", "GlossCol",
          "TransDir", "TransInd", "TransCol", "Emit", "Env"]
LAYERS = ["Diffuse", "Glossy", "Transmission", "Emission", "Environment"]


def make_passes(w=40, h=28, seed=1):
    """{pass name: H x W x 3 float32} plus "Normal" and "Depth" features; Combined from the identity."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    p = {}
    for i, (_, short) in enumerate(COMPONENTS):
        p[short + "Dir"] = rng.exponential(0.5 + i, (h, w, 3)).astype(np.float32)
        p[short + "Ind"] = rng.exponential(0.2, (h, w, 3)).astype(np.float32)
        ramp = (0.2 + 0.6 * xx / w)[..., None] * np.array([1.0, 0.8 - 0.2 * i, 0.5], np.float32)
        p[short + "Col"] = np.where((xx < w // 2)[..., None] == (i == 0), ramp, 0.1 * ramp).astype(np.float32)
    p["Emit"] = np.where(((xx - 8) ** 2 + (yy - 8) ** 2 < 9)[..., None], 5.0, 0.0).astype(np.float32) * np.ones(3, np.float32)
    p["Env"] = np.where((yy < 3)[..., None], 0.7, 0.0).astype(np.float32) * np.array([0.5, 0.6, 1.0], np.float32)
    comb = np.zeros((h, w, 3), np.float32)
    for _, short in COMPONENTS:
        comb += (p[short + "Dir"] + p[short + "Ind"]) * p[short + "Col"]
    p["Combined"] = comb + p["Emit"] + p["Env"]
    n = np.zeros((h, w, 3), np.float32)
    n[..., 2] = 1.0
    n[:, w // 2:, 0] = 1.0
    n[:, w // 2:, 2] = 0.0
    p["Normal"] = n
    p["Depth"] = (5.0 + xx / w)[..., None]
    return p


def write_multilayer(path, passes, leave_out=()):
    """Writes the passes as ViewLayer.<pass>.R/G/B (Depth: .Z; Normal: .X/.Y/.Z; Combined: +A),
    leaving out the passes named in leave_out."""
    names, planes = [], []
    for name, img in passes.items():
        if name in leave_out:
            continue
        if name == "Depth":
            suffixes = ["Z"]
        elif name == "Normal":
            suffixes = ["X", "Y", "Z"]
        else:
            suffixes = ["R", "G", "B"]
        for c, s in enumerate(suffixes):
            names.append("%s.%s.%s" % (LAYER, name, s))
            planes.append(img[..., c])
        if name == "Combined":
            names.append(LAYER + ".Combined.A")
            planes.append(np.ones(img.shape[:2], np.float32))
    tu.write_exr(path, np.stack(planes, axis=-1), names)


def write_single(path, rgb, passes, albedo):
    """A file whose Combined is `rgb`, with the same feature passes and `albedo` as its albedo
    (a component's filter sees its colour pass as albedo): the oracle's input."""
    tu.write_exr(path, np.concatenate([rgb, passes["Normal"], passes["Depth"], albedo], axis=-1),
                 ["%s.Combined.%s" % (LAYER, c) for c in "RGB"] +
                 ["%s.Normal.%s" % (LAYER, c) for c in "XYZ"] + [LAYER + ".Depth.Z"] +
                 ["%s.Denoising Albedo.%s" % (LAYER, c) for c in "RGB"])


def component_layer_channels(name, layer=LAYER):
    return ["%s.Denoised.%s.%s" % (layer, name, c) for c in "RGB"]
