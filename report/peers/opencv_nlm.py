"""The classical peer of `mcrecon report`: OpenCV's non-local means on a float RGB render.

    /usr/bin/python3 report/peers/opencv_nlm.py --input COLOUR --output OUT [--h H]

COLOUR and OUT are EXR or PFM (OUT's format by its extension). Both are read with OpenImageIO and
EXR written with it; PFM is written here (the OpenImageIO 2.4 of Debian 12 reads PFM, writes none):
"PF" (3 channels) or "Pf" (1), little-endian scale -1, rows bottom to top.
OpenCV's non-local means takes 8- or 16-bit images only, so the float colour goes through a
log-like tone curve to 16 bits and back:

    v = 65535 * log1p(k x) / log1p(k M)        x = expm1(v / 65535 * log1p(k M)) / k

M is the largest value, m the median of the positive values, and k = (M - 2m) / m^2 puts m at
mid-range (v = 32767.5); when M <= 2m the curve is linear (v = 65535 x / M). Negative values
(which a tone curve on [0, M] cannot hold) are clamped to 0 and counted, non-finite ones replaced
by 0 and counted, on stderr.

Denoising: cv2.fastNlMeansDenoising on the three colour channels together (16-bit needs
normType=NORM_L1), OpenCV's default 7x7 patches and 21x21 search window. A fourth or later channel
(alpha) is passed through. Without --h, h comes from a noise estimate of the tone-mapped image:
sigma = the median absolute deviation (x 1.4826) of the residual of Immerkaer's 3x3 Laplacian
difference mask [1 -2 1; -2 4 -2; 1 -2 1] / 6 (unit gain on white noise, zero on linear ramps), per
channel, averaged. OpenCV weighs a patch by exp(-d^2 / (h^2 c)) with d the patch's mean absolute
difference summed over the c channels; two noisy copies of one patch differ by about
c * 2 sigma / sqrt(pi), so h = sqrt(c) * 2 sigma / sqrt(pi) gives them weight 1/e. That relation
is derived from OpenCV's weight formula, not fitted to any scene or reference.

Errors (unreadable input, unknown output extension, failed write) print a message naming the file
and exit 2. The output is written to a temp file in its folder and renamed.
"""
import argparse
import math
import os
import sys

import numpy as np

PROG = "opencv_nlm"
FORMATS = (".exr", ".pfm")


class PeerError(Exception):
    pass


def read_float(path):
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise PeerError("cannot read '%s': %s" % (path, oiio.geterror() or "not an image"))
    try:
        spec = inp.spec()
        names = list(spec.channelnames)
        px = inp.read_image(oiio.FLOAT)
        if px is None:
            raise PeerError("cannot read pixels of '%s': %s" % (path, inp.geterror()))
    finally:
        inp.close()
    px = np.array(px, dtype=np.float32)
    if px.ndim == 2:
        px = px[:, :, None]
    return px, names


def write_pfm(path, px):
    if px.shape[2] not in (1, 3):
        raise PeerError("cannot write '%s': PFM holds 1 or 3 channels, not %d" % (path, px.shape[2]))
    with open(path, "wb") as f:
        f.write(b"%s\n%d %d\n-1.0\n" % (b"PF" if px.shape[2] == 3 else b"Pf", px.shape[1], px.shape[0]))
        f.write(np.ascontiguousarray(px[::-1], dtype="<f4").tobytes())


def write_float(path, px, names):
    import OpenImageIO as oiio
    d, base = os.path.split(os.path.abspath(path))
    ext = os.path.splitext(base)[1]
    tmp = os.path.join(d, ".%s.tmp%d%s" % (base, os.getpid(), ext))  # same folder, real extension
    try:
        if ext.lower() == ".pfm":
            write_pfm(tmp, px)
            os.replace(tmp, path)
            return
        spec = oiio.ImageSpec(px.shape[1], px.shape[0], px.shape[2], oiio.FLOAT)
        if ext.lower() == ".exr" and len(names) == px.shape[2]:
            spec.channelnames = tuple(names)
        out = oiio.ImageOutput.create(tmp)
        if out is None:
            raise PeerError("cannot write '%s': %s" % (path, oiio.geterror()))
        ok = out.open(tmp, spec) and out.write_image(np.ascontiguousarray(px))
        err = out.geterror()
        out.close()
        if not ok:
            raise PeerError("cannot write '%s': %s" % (path, err))
        os.replace(tmp, path)
    except OSError as e:
        raise PeerError("cannot write '%s': %s" % (path, e.strerror or e))
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


class ToneCurve:
    """The invertible log-like map of [0, M] onto [0, 1] described above."""

    def __init__(self, colour):
        pos = colour[colour > 0]
        self.M = float(colour.max()) if colour.size else 0.0
        m = float(np.median(pos)) if pos.size else 0.0
        self.k = (self.M - 2.0 * m) / (m * m) if m > 0 and self.M > 2.0 * m else 0.0
        self.L = math.log1p(self.k * self.M) if self.k > 0 else 1.0

    def forward(self, x):
        if self.M <= 0:
            return np.zeros_like(x)
        if self.k > 0:
            return np.log1p(self.k * x) / self.L
        return x / self.M

    def inverse(self, v):
        if self.M <= 0:
            return np.zeros_like(v)
        if self.k > 0:
            return np.expm1(v * self.L) / self.k
        return v * self.M


def noise_sigma(img):
    """Per-channel MAD noise estimate on the Laplacian-difference residual, averaged over channels."""
    if img.shape[0] < 3 or img.shape[1] < 3:
        return 0.0
    sig = []
    for c in range(img.shape[2]):
        a = img[:, :, c].astype(np.float64)
        r = (a[:-2, :-2] - 2 * a[:-2, 1:-1] + a[:-2, 2:]
             - 2 * a[1:-1, :-2] + 4 * a[1:-1, 1:-1] - 2 * a[1:-1, 2:]
             + a[2:, :-2] - 2 * a[2:, 1:-1] + a[2:, 2:]) / 6.0
        sig.append(1.4826 * float(np.median(np.abs(r - np.median(r)))))
    return float(np.mean(sig))


def denoise(px, h, log):
    import cv2
    nc = 3 if px.shape[2] >= 3 else 1
    colour = px[:, :, :nc]
    bad = ~np.isfinite(colour)
    if bad.any():
        log("replaced %d non-finite values by 0" % int(bad.sum()))
        colour = np.where(bad, 0.0, colour)
    neg = colour < 0
    if neg.any():
        log("clamped %d negative values to 0" % int(neg.sum()))
        colour = np.maximum(colour, 0.0)
    curve = ToneCurve(colour)
    v16 = np.clip(np.rint(curve.forward(colour.astype(np.float64)) * 65535.0), 0, 65535).astype(np.uint16)
    if h is None:
        sigma = noise_sigma(v16)
        h = math.sqrt(nc) * 2.0 * sigma / math.sqrt(math.pi)
        log("noise sigma %.4g (16-bit tone-mapped units), h %.4g" % (sigma, h))
    if h > 0:
        src = np.ascontiguousarray(v16 if nc == 3 else v16[:, :, 0])
        out = cv2.fastNlMeansDenoising(src, h=[float(h)], templateWindowSize=7, searchWindowSize=21,
                                       normType=cv2.NORM_L1)
        v16 = out.reshape(v16.shape)
    result = px.copy()
    result[:, :, :nc] = curve.inverse(v16.astype(np.float64) / 65535.0).astype(np.float32)
    return result


def main(argv):
    ap = argparse.ArgumentParser(prog=PROG, description="OpenCV non-local means on a float RGB image "
                                 "(EXR or PFM), through a 16-bit log-like tone curve.")
    ap.add_argument("--input", required=True, help="noisy colour, EXR or PFM")
    ap.add_argument("--output", required=True, help="denoised colour, EXR or PFM (by extension)")
    ap.add_argument("--h", type=float, default=None,
                    help="OpenCV filter strength in 16-bit tone-mapped units (default: from a noise estimate)")
    a = ap.parse_args(argv[1:])

    def log(msg):
        print("%s: %s: %s" % (PROG, a.input, msg), file=sys.stderr, flush=True)

    try:
        if os.path.splitext(a.output)[1].lower() not in FORMATS:
            raise PeerError("cannot write '%s': the extension must be .exr or .pfm" % a.output)
        if a.h is not None and not (math.isfinite(a.h) and a.h >= 0):
            raise PeerError("--h must be a finite number >= 0, got %s" % a.h)
        px, names = read_float(a.input)
        write_float(a.output, denoise(px, a.h, log), names)
    except PeerError as e:
        print("%s: %s" % (PROG, e), file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
