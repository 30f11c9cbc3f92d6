"""Shared helpers for the end-to-end Python tests: locating the CLI, running it, EXR I/O.

The tests are run by ctest as `/usr/bin/python3 tests/python/test_x.py` with
MCRECON_BIN (the mcrecon CLI) and MCRECON_SOURCE_DIR (the repository root) in the environment.
"""
import json
import os
import subprocess

import numpy as np
import OpenImageIO as oiio

_HERE = os.path.dirname(os.path.abspath(__file__))


def source_dir():
    """Repository root: $MCRECON_SOURCE_DIR, else two levels above this file."""
    return os.environ.get("MCRECON_SOURCE_DIR") or os.path.dirname(os.path.dirname(_HERE))


def mcrecon_bin():
    """Path of the mcrecon CLI: $MCRECON_BIN, else build/bin/mcrecon in the source tree."""
    return os.environ.get("MCRECON_BIN") or os.path.join(source_dir(), "build", "bin", "mcrecon")


def run_cli(*args, check=True, timeout=300):
    """Runs the CLI with the given arguments; returns the CompletedProcess (text mode)."""
    proc = subprocess.run([mcrecon_bin(), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError("mcrecon %s exited %d\nstdout:\n%s\nstderr:\n%s" % (
            " ".join(map(str, args)), proc.returncode, proc.stdout, proc.stderr))
    return proc


def run_cli_json(*args, **kwargs):
    """Runs the CLI and parses its standard output as one JSON document."""
    proc = run_cli(*args, **kwargs)
    try:
        return json.loads(proc.stdout)
    except ValueError as e:
        raise AssertionError("mcrecon %s printed no valid JSON (%s):\n%s"
                             % (" ".join(map(str, args)), e, proc.stdout))


def write_exr(path, pixels, channel_names=None):
    """Writes an H x W x C array as a float EXR (channel names default to R, G, B, A...)."""
    pixels = np.ascontiguousarray(pixels, dtype=np.float32)
    if pixels.ndim == 2:
        pixels = pixels[:, :, np.newaxis]
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, "float")
    if channel_names is not None:
        spec.channelnames = tuple(channel_names)
    out = oiio.ImageOutput.create(path)
    if out is None:
        raise RuntimeError("cannot create an image writer for %s: %s" % (path, oiio.geterror()))
    try:
        if not out.open(path, spec) or not out.write_image(pixels):
            raise RuntimeError("writing %s failed: %s" % (path, out.geterror()))
    finally:
        out.close()


def read_channels(path, names):
    """Reads the named channels of an image (searching every subimage/part) as H x W x len(names)
    float32. Raises KeyError naming the channels that are missing."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError("cannot open %s: %s" % (path, oiio.geterror()))
    try:
        found = {}
        sub = 0
        while inp.seek_subimage(sub, 0):
            spec = inp.spec()
            wanted = [n for n in names if n in spec.channelnames and n not in found]
            if wanted:
                data = inp.read_image(sub, 0, 0, spec.nchannels, "float")
                if data is None:
                    raise RuntimeError("reading %s failed: %s" % (path, inp.geterror()))
                data = np.asarray(data).reshape(spec.height, spec.width, spec.nchannels)
                for n in wanted:
                    found[n] = data[:, :, list(spec.channelnames).index(n)]
            sub += 1
    finally:
        inp.close()
    missing = [n for n in names if n not in found]
    if missing:
        raise KeyError("%s has no channel(s) %s" % (path, ", ".join(missing)))
    return np.stack([found[n] for n in names], axis=-1).astype(np.float32)
