"""Files for the bad-input matrix (test_bad_input_matrix.py, tests/blender/test_addon_bad_input.py):
a tiny Blender-like EXR, broken copies of it (cut, bit-flipped, a header claiming a huge image),
private device nodes and FIFOs, and a snapshot of a directory (content hashes, file types) to
prove that a run left every input byte-identical and no output or temp file behind.
"""
import hashlib
import os
import stat
import struct

import numpy as np
import OpenImageIO as oiio

W, H = 16, 12
LAYER = "ViewLayer"
CHANNELS = ["Combined.R", "Combined.G", "Combined.B", "Combined.A",
            "Denoising Albedo.R", "Denoising Albedo.G", "Denoising Albedo.B",
            "Normal.X", "Normal.Y", "Normal.Z", "Position.X", "Position.Y", "Position.Z",
            "Depth.Z", "Vector.X", "Vector.Y", "Vector.Z", "Vector.W"]
TEMP_MARKS = (".mcrecon-tmp.", ".temp.")  # ours, and oiiotool's own temp names


def blender_channels():
    return ["%s.%s" % (LAYER, c) for c in CHANNELS]


def blender_pixels(seed=0, w=W, h=H):
    """Plausible passes: colour in [0, 1), alpha 1, albedo in [0.2, 1), unit normals, positions,
    depth > 0, small motion."""
    rng = np.random.default_rng(seed)
    px = np.zeros((h, w, len(CHANNELS)), np.float32)
    px[..., 0:3] = rng.random((h, w, 3))
    px[..., 3] = 1
    px[..., 4:7] = 0.2 + 0.8 * rng.random((h, w, 3))
    n = rng.normal(size=(h, w, 3)) + [0, 0, 3]
    px[..., 7:10] = n / np.linalg.norm(n, axis=-1, keepdims=True)
    px[..., 10:13] = rng.random((h, w, 3)) * 4
    px[..., 13] = 1 + rng.random((h, w))
    px[..., 14:18] = rng.random((h, w, 4)) - 0.5
    return px


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def write_bytes(path, data):
    with open(path, "wb") as f:
        f.write(data)


def write_exr(path, pixels, names, compression="zip", origin=(0, 0)):
    pixels = np.ascontiguousarray(pixels, dtype=np.float32)
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, "float")
    spec.channelnames = tuple(names)
    spec.x, spec.y = origin
    spec.attribute("compression", compression)
    out = oiio.ImageOutput.create(path)
    assert out is not None, oiio.geterror()
    try:
        assert out.open(path, spec) and out.write_image(pixels), out.geterror()
    finally:
        out.close()


def write_render(path, seed=0, w=W, h=H, pixels=None, compression="zip"):
    """A Blender-like multilayer EXR (one view layer, the passes every filter uses)."""
    write_exr(path, blender_pixels(seed, w, h) if pixels is None else pixels, blender_channels(), compression)


def write_multipart(path, parts):
    """parts: [(name, pixels H x W x C, channel names, origin)] as one multi-part EXR."""
    specs = []
    for name, px, names, origin in parts:
        h, w, c = px.shape
        s = oiio.ImageSpec(w, h, c, "float")
        s.channelnames = tuple(names)
        s.x, s.y = origin
        s.full_x, s.full_y, s.full_width, s.full_height = 0, 0, W, H  # one display window
        s.attribute("name", name)
        specs.append(s)
    out = oiio.ImageOutput.create(path)
    assert out is not None, oiio.geterror()
    try:
        assert out.open(path, specs), out.geterror()
        for i, (_, px, _, _) in enumerate(parts):
            if i:
                assert out.open(path, specs[i], "AppendSubimage"), out.geterror()
            assert out.write_image(np.ascontiguousarray(px, np.float32)), out.geterror()
    finally:
        out.close()


def header_attributes(data):
    """(name, type, value offset, size) of each attribute of a single-part EXR header, and the
    offset where the header ends (the chunk offset table begins)."""
    assert data[:4] == b"\x76\x2f\x31\x01", "not an OpenEXR file"
    pos, attrs = 8, []
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        attrs.append((data[pos:name_end].decode(), data[name_end + 1:type_end].decode(), type_end + 5, size))
        pos = type_end + 5 + size
    return attrs, pos + 1


def claim_size(src, dst, width, height):
    """Copies the EXR src to dst with its data and display windows patched to width x height:
    a tiny file whose header claims a huge image."""
    data = bytearray(read_bytes(src))
    attrs, _ = header_attributes(data)
    for name, typ, off, size in attrs:
        if name in ("dataWindow", "displayWindow"):
            assert typ == "box2i" and size == 16
            struct.pack_into("<iiii", data, off, 0, 0, width - 1, height - 1)
    write_bytes(dst, bytes(data))


def flip_offset_table(src, dst):
    """Copies src to dst with one bit flipped in the high bytes of the first chunk offset: the
    offset then points far beyond the end of the file."""
    data = bytearray(read_bytes(src))
    _, table = header_attributes(data)
    data[table + 5] ^= 0x40
    write_bytes(dst, bytes(data))


def cut(src, dst, n):
    write_bytes(dst, read_bytes(src)[:n])


def mknod_char(path, major, minor):
    """A private character device node (never a real /dev node)."""
    os.mknod(path, stat.S_IFCHR | 0o600, os.makedev(major, minor))


def snapshot(root):
    """{relative path: what it is} for everything under root, without following links or
    opening anything but regular files: ('file', sha256) / ('dir',) / ('link', target) /
    ('fifo',) / ('chr', major, minor) / ('other', mode)."""
    snap = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = os.path.join(dirpath, name)
            st = os.lstat(p)
            m = st.st_mode
            if stat.S_ISLNK(m):
                kind = ("link", os.readlink(p))
            elif stat.S_ISDIR(m):
                kind = ("dir",)
            elif stat.S_ISREG(m):
                h = hashlib.sha256()
                with open(p, "rb") as f:
                    for block in iter(lambda: f.read(1 << 20), b""):
                        h.update(block)
                kind = ("file", h.hexdigest(), st.st_ino)
            elif stat.S_ISFIFO(m):
                kind = ("fifo",)
            elif stat.S_ISCHR(m):
                kind = ("chr", os.major(st.st_rdev), os.minor(st.st_rdev))
            else:
                kind = ("other", m)
            snap[os.path.relpath(p, root)] = kind
    return snap


def snapshot_diff(before, after):
    """A readable list of what changed between two snapshots ('' when nothing)."""
    lines = []
    for p in sorted(set(before) | set(after)):
        a, b = before.get(p), after.get(p)
        if a == b:
            continue
        if a is None:
            lines.append("  new:     %s (%s)" % (p, b[0]))
        elif b is None:
            lines.append("  removed: %s (was %s)" % (p, a[0]))
        else:
            lines.append("  changed: %s (%s -> %s)" % (p, describe(a), describe(b)))
    return "\n".join(lines)


def describe(kind):
    if kind[0] == "file":
        return "file %s.. inode %d" % (kind[1][:8], kind[2])
    return " ".join(map(str, kind))


def temp_files(root):
    return [p for p in snapshot(root) if any(m in os.path.basename(p) for m in TEMP_MARKS)]


def read_rgba(path):
    """(width, height, R,G,B,A as H x W x 4 float32) of an output file."""
    inp = oiio.ImageInput.open(path)
    assert inp is not None, "cannot open %s: %s" % (path, oiio.geterror())
    try:
        spec = inp.spec()
        names = list(spec.channelnames)
        px = inp.read_image(0, 0, 0, spec.nchannels, "float")
        assert px is not None, inp.geterror()
        px = np.asarray(px).reshape(spec.height, spec.width, spec.nchannels)
        missing = [c for c in "RGBA" if c not in names]
        assert not missing, "%s has no channel(s) %s (has %s)" % (path, missing, names)
        return spec.width, spec.height, px[..., [names.index(c) for c in "RGBA"]]
    finally:
        inp.close()


def claim_size_with_table(src, dst, width, height, lines_per_chunk=16):
    """Like claim_size, but with a complete chunk offset table for the claimed height (every entry
    pointing at the file's one real chunk): the reader gets past the table, so a front end that
    sizes its buffers by the header allocates the whole claimed image before the read fails."""
    data = bytearray(read_bytes(src))
    attrs, table = header_attributes(data)
    compression = [data[off] for name, typ, off, size in attrs if name == "compression"][0]
    assert compression == 3, "needs a ZIP-compressed source (16 lines per chunk)"
    n_old = (H + lines_per_chunk - 1) // lines_per_chunk
    chunks = bytes(data[table + 8 * n_old:])
    header = bytearray(data[:table])
    for name, typ, off, size in attrs:
        if name in ("dataWindow", "displayWindow"):
            struct.pack_into("<iiii", header, off, 0, 0, width - 1, height - 1)
    n_new = (height + lines_per_chunk - 1) // lines_per_chunk
    first = len(header) + 8 * n_new
    write_bytes(dst, bytes(header) + struct.pack("<%dQ" % n_new, *([first] * n_new)) + chunks)
