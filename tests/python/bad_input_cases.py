"""The bad-input matrix: one row per case, with how each front end is driven on it.

A case builds its inputs in a fresh directory (`build(c)`, c.d is the directory) and gives, per
front end, what to run:
  cli          mcrecon arguments                         (exit status 2 expected on bad input)
  oiio_read    oiiotool arguments, the plugin as reader  (`IN.mcrecon?filter=...`)
  oiio_iconfig oiiotool arguments, settings by --iconfig
  oiio_write   oiiotool arguments, the plugin as writer  (-o:fileformatname=mcrecon)
  py           Python statements using `mcrecon` and `np` (mcrecon.Error with a .kind expected)
`mentions`: what the message must contain (a tuple: any one of its strings), naming the file,
pass or parameter and repeating what was given (`mentions_fe`: per front end, where it differs).
Cases with expect="ok" must succeed and write exactly `outputs` (complete, finite; `nonzero`: no
zero RGB either); "ok_or_refused": either that or a refusal (a limit the issue leaves to the fix,
such as the widest # run).
"""
import os
import shutil
import subprocess
from types import SimpleNamespace

import numpy as np

import bad_input_files as bf

FLT_MAX = float(np.finfo(np.float32).max)
INT_MAX = 2147483647


class Case(SimpleNamespace):
    def __init__(self, name, fe, build=None, expect="error", mentions=(), outputs=(), mutable=(),
                 nonzero=False, same_as_threads0=False, size=(bf.W, bf.H), note="", mentions_fe=None):
        super().__init__(name=name, fe=fe, build=build or (lambda c: None), expect=expect,
                         mentions=mentions, mentions_fe=mentions_fe or {}, outputs=outputs, mutable=mutable, nonzero=nonzero,
                         same_as_threads0=same_as_threads0, size=size, note=note)


def ctx(d):
    """The paths a case refers to; `in.exr` is always written (a 16x12 Blender-like render)."""
    c = SimpleNamespace(d=d, inp=os.path.join(d, "in.exr"), out=os.path.join(d, "out.exr"))
    bf.write_render(c.inp)
    c.p = lambda name: os.path.join(d, name)
    return c


# ---------------------------------------------------------------------- front-end shorthands

def cli_denoise(src, out="{out}", *extra, filt="box"):
    return lambda c: ["denoise", src.format(**vars(c)), "-o", out.format(**vars(c)), "-f", filt,
                      *[e.format(**vars(c)) for e in extra]]


def py_file(src, out="{out}", filt="box", **kw):
    args = "".join(", %s=%s" % (k, v) for k, v in kw.items())
    return lambda c: "mcrecon.denoise_file(%r, %r, %r%s)" % (src.format(**vars(c)), out.format(**vars(c)), filt, args)


def oiio_read(src, query="filter=box"):
    return lambda c: ["%s.mcrecon?%s" % (src.format(**vars(c)), query), "-o", c.out]


def oiio_write(out, *attrs, src="{inp}"):
    return lambda c: [src.format(**vars(c)), "--attrib", "mcrecon:filter", "box", *attrs,
                      "-o:fileformatname=mcrecon", out.format(**vars(c))]


def input_fe(src):
    """Every front end reading one bad input file."""
    return dict(cli=cli_denoise(src), cli_info=lambda c: ["info", src.format(**vars(c))],
                oiio_read=oiio_read(src), py=py_file(src))


def output_fe(out, oiio=True):
    """Every front end writing `out` from the good input."""
    fe = dict(cli=cli_denoise("{inp}", out), py=py_file("{inp}", out))
    if oiio:
        fe["oiio_write"] = oiio_write(out)
    return fe


def param_fe(query, typed, py_params, filt="box"):
    """A filter parameter through every front end: --set, ?query, --iconfig (typed), params=."""
    key, value = query.split("=", 1)
    return dict(cli=cli_denoise("{inp}", "{out}", "--set", query, filt=filt),
                oiio_read=oiio_read("{inp}", "filter=%s&%s" % (filt, query)),
                oiio_iconfig=lambda c: ["--iconfig", "mcrecon:filter", filt,
                                        *(["--iconfig:type=" + typed] if typed else ["--iconfig"]),
                                        "mcrecon:" + key, value, c.inp + ".mcrecon", "-o", c.out],
                py=lambda c: "mcrecon.denoise_file(%r, %r, %r, %s)" % (c.inp, c.out, filt, py_params))


# ---------------------------------------------------------------------- builders

def b_cut(n):
    def build(c):
        bf.cut(c.inp, c.p("cut.exr"), n(bf.read_bytes(c.inp)))
    return build


def b_seq(c, frames=(1, 2), pattern="in_%04d.exr"):
    for f in frames:
        bf.write_render(c.p(pattern % f), seed=f)


def b_pixels(fn):
    def build(c):
        px = bf.blender_pixels(3)
        fn(px)
        bf.write_render(c.p("odd.exr"), pixels=px)
    return build


def nan_inf(px):
    for k in range(px.shape[2]):
        if bf.CHANNELS[k] == "Combined.A":
            continue
        px[k % bf.H, 0, k] = np.nan
        px[(k + 3) % bf.H, 5, k] = np.inf
        px[(k + 6) % bf.H, 9, k] = -np.inf
        px[:, 15, k] = np.nan


def flt_max(px):
    px[..., 0:3] = FLT_MAX


def b_chattr_dir(c):
    os.mkdir(c.p("ro"))
    r = subprocess.run(["chattr", "+i", c.p("ro")], capture_output=True, text=True)
    if r.returncode != 0:
        raise Skip("chattr +i is not available here (%s): as root a chmod 0555 directory is "
                   "writable, so the read-only directory case cannot be made" % r.stderr.strip())
    c.cleanup = lambda: subprocess.run(["chattr", "-i", c.p("ro")], capture_output=True)


class Skip(Exception):
    pass


def b_mknod(name, major, minor):
    def build(c):
        try:
            bf.mknod_char(c.p(name), major, minor)
        except PermissionError as e:
            raise Skip("cannot create a private device node (%s)" % e)
    return build


def b_multipart(c):
    px = bf.blender_pixels(5)
    colour = px[..., 0:4]
    normal = px[2:10, 4:12, 7:10]
    bf.write_multipart(c.p("parts.exr"), [("ViewLayer", colour, ["R", "G", "B", "A"], (0, 0)),
                                          ("normal", normal, ["N.X", "N.Y", "N.Z"], (4, 2))])


def b_resume(c):
    b_seq(c)
    bf.write_render(c.p("full.exr"), seed=9, w=bf.W, h=bf.H)
    data = bf.read_bytes(c.p("full.exr"))
    os.remove(c.p("full.exr"))
    bf.write_bytes(c.p("out_0001.exr"), data[:len(data) // 2])


def b_demo(c):
    c.samples = os.path.join(os.environ.get("MCRECON_SOURCE_DIR") or
                             os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                             "samples", "data")


LONG = "a" * 250 + ".exr"          # 254 bytes: a valid name (NAME_MAX is 255)
HASH40 = "o_" + "#" * 40 + ".exr"


def _cases():
    C = []

    def add(*a, **k):
        C.append(Case(*a, **k))

    # ------------------------------------------------------------------ unreadable inputs
    add("missing_file", input_fe("{d}/nosuch.exr"), mentions=["nosuch.exr"])
    add("directory_input", input_fe("{d}/adir.exr"), build=lambda c: os.mkdir(c.p("adir.exr")),
        mentions=["adir.exr"])
    add("empty_file", input_fe("{d}/empty.exr"), build=lambda c: bf.write_bytes(c.p("empty.exr"), b""),
        mentions=["empty.exr"])
    add("text_named_exr", input_fe("{d}/notes.exr"),
        build=lambda c: bf.write_bytes(c.p("notes.exr"), b"this is not an image\n" * 20), mentions=["notes.exr"])
    header_end = lambda data: bf.header_attributes(data)[1] + 4  # inside the offset table
    for label, n in (("cut_8", lambda data: 8), ("cut_100", lambda data: 100), ("cut_in_offset_table", header_end),
                     ("cut_half", lambda data: len(data) // 2), ("cut_last_byte", lambda data: len(data) - 1)):
        add("truncated_" + label, input_fe("{d}/cut.exr"), build=b_cut(n), mentions=["cut.exr"])
    add("bitflip_offset_table", input_fe("{d}/flip.exr"),
        build=lambda c: bf.flip_offset_table(c.inp, c.p("flip.exr")), mentions=["flip.exr"])

    def b_claim(w, h, name):
        def build(c):
            bf.write_exr(c.p("small_rgb.exr"), np.full((bf.H, bf.W, 3), 0.5), ["R", "G", "B"])
            bf.claim_size_with_table(c.p("small_rgb.exr"), c.p(name), w, h)
            os.remove(c.p("small_rgb.exr"))
        return build
    add("header_claims_100000x100000", input_fe("{d}/huge.exr"), build=b_claim(100000, 100000, "huge.exr"),
        mentions=["huge.exr"], note="50 KB file: the plugin allocates 120 GB and aborts (issue 4)")
    add("header_claims_100000x100000_no_table", input_fe("{d}/huge.exr"),
        build=lambda c: bf.claim_size(c.inp, c.p("huge.exr"), 100000, 100000), mentions=["huge.exr"])
    add("header_claims_800MB_from_5KB", input_fe("{d}/claims.exr"), build=b_claim(8192, 8192, "claims.exr"),
        mentions=["claims.exr"], note="memory set by the header, not the file (issue 6)")
    add("fifo_input", input_fe("{d}/pipe.exr"), build=lambda c: os.mkfifo(c.p("pipe.exr")),
        mentions=["pipe.exr"], note="hangs (issue 5)")
    add("chardev_zero_input", input_fe("{d}/zero.exr"), build=b_mknod("zero.exr", 1, 5),
        mentions=["zero.exr"], note="hangs (issue 5)")
    add("chardev_urandom_input", input_fe("{d}/urandom.exr"), build=b_mknod("urandom.exr", 1, 9),
        mentions=["urandom.exr"], note="hangs (issue 5)")

    # ------------------------------------------------------------------ outputs over inputs / odd targets
    add("output_same_path", output_fe("{inp}", oiio=False), mentions=["in.exr"])
    add("output_dot_spelling", output_fe("{d}/./in.exr", oiio=False), mentions=["in.exr"])
    add("output_dotdot_spelling", output_fe("{d}/sub/../in.exr", oiio=False),
        build=lambda c: os.mkdir(c.p("sub")), mentions=["in.exr"])
    add("output_symlink_to_input", output_fe("{d}/link.exr", oiio=False),
        build=lambda c: os.symlink("in.exr", c.p("link.exr")), mentions=["link.exr"])
    add("output_hardlink_to_input", output_fe("{d}/hard.exr", oiio=False),
        build=lambda c: os.link(c.inp, c.p("hard.exr")), mentions=["hard.exr"])
    add("output_chardev_null", output_fe("{d}/null.exr"), build=b_mknod("null.exr", 1, 3),
        mentions=["null.exr"], note="replaced by a regular file (issue 2)")
    add("output_fifo", output_fe("{d}/fifo_out.exr"), build=lambda c: os.mkfifo(c.p("fifo_out.exr")),
        mentions=["fifo_out.exr"])
    add("output_directory", output_fe("{d}/outdir.exr"), build=lambda c: os.mkdir(c.p("outdir.exr")),
        mentions=["outdir.exr"])
    add("output_in_missing_directory", output_fe("{d}/nodir/out.exr"), mentions=["nodir"])
    add("output_in_readonly_directory", output_fe("{d}/ro/out.exr"), build=b_chattr_dir, mentions=["ro/out.exr"],
        note="chattr +i: as root a chmod 0555 directory stays writable")
    add("output_name_254_bytes_ok", output_fe("{d}/" + LONG, oiio=False), expect="ok", outputs=[LONG],
        note="valid name refused: temp name > 255 bytes (issue 8)")

    # ------------------------------------------------------------------ sequences and frame ranges
    seq_in = "{d}/in_####.exr"
    add("sequence_hash_run_40_ok",
        dict(cli=cli_denoise(seq_in, "{d}/" + HASH40, "--frames", "1-2"),
             py=lambda c: "mcrecon.denoise_sequence(%r, %r, 1, 2, 'box')" % (c.p("in_####.exr"), c.p(HASH40))),
        build=b_seq, expect="ok_or_refused", outputs=["o_%040d.exr" % f for f in (1, 2)], mentions=[HASH40],
        note="frames written over each other (issue 3)")
    add("sequence_output_without_hash",
        dict(cli=cli_denoise(seq_in, "{out}", "--frames", "1-2"),
             py=lambda c: "mcrecon.denoise_sequence(%r, %r, 1, 2, 'box')" % (c.p("in_####.exr"), c.out)),
        build=b_seq, mentions=["out.exr"])
    add("frames_reversed",
        dict(cli=cli_denoise(seq_in, "{d}/o_####.exr", "--frames", "7-3"),
             py=lambda c: "mcrecon.denoise_sequence(%r, %r, 7, 3, 'box')" % (c.p("in_####.exr"), c.p("o_####.exr"))),
        build=b_seq, mentions=["7", "3"])
    add("frames_non_numeric", dict(cli=cli_denoise(seq_in, "{d}/o_####.exr", "--frames", "one-two")),
        build=b_seq, mentions=["one-two"])
    add("frames_ending_at_INT_MAX_ok",
        dict(cli=cli_denoise("{d}/in_#.exr", "{d}/o_#.exr", "--frames", "%d-%d" % (INT_MAX - 1, INT_MAX)),
             py=lambda c: "mcrecon.denoise_sequence(%r, %r, %d, %d, 'box')" % (c.p("in_#.exr"), c.p("o_#.exr"),
                                                                             INT_MAX - 1, INT_MAX)),
        build=lambda c: b_seq(c, (INT_MAX - 1, INT_MAX), "in_%d.exr"), expect="ok",
        outputs=["o_%d.exr" % f for f in (INT_MAX - 1, INT_MAX)], note="loop counter overflow (issue 8)")
    add("resume_truncated_output_ok", dict(cli=cli_denoise(seq_in, "{d}/out_####.exr", "--frames", "1-2", "--resume")),
        build=b_resume, expect="ok", outputs=["out_0001.exr", "out_0002.exr"], mutable=["out_0001.exr"],
        note="--resume keeps a truncated output (issue 9)")

    # ------------------------------------------------------------------ filters and parameters
    add("unknown_filter",
        dict(cli=cli_denoise("{inp}", "{out}", filt="nosuch_filter"), oiio_read=oiio_read("{inp}", "filter=nosuch_filter"),
             oiio_iconfig=lambda c: ["--iconfig", "mcrecon:filter", "nosuch_filter", c.inp + ".mcrecon", "-o", c.out],
             oiio_write=oiio_write("{out}", "--attrib", "mcrecon:filter", "nosuch_filter"),
             py=py_file("{inp}", filt="nosuch_filter")),
        mentions=["nosuch_filter"])
    add("unknown_parameter", param_fe("nosuch_param=1", "int", "{'nosuch_param': 1}"), mentions=["nosuch_param"])
    add("out_of_range_1e20", param_fe("radius=1e20", "float", "{'radius': 1e20}"),
        mentions=["radius", ("1e20", "1e+20")], note="echoed as 1e+20; bare RuntimeError in Python (issue 9)",
        mentions_fe={"cli": ["radius", "1e20"], "oiio_read": ["radius", "1e20"]})  # as typed
    add("out_of_range_float_1e20", param_fe("spatial_sigma=1e20", "float", "{'spatial_sigma': 1e20}", "bilateral"),
        mentions=["spatial_sigma", ("1e20", "1e+20")], note="echoed as 1e+20 (issue 9)",
        mentions_fe={"cli": ["spatial_sigma", "1e20"], "oiio_read": ["spatial_sigma", "1e20"]})
    add("py_parameter_int_beyond_int64", dict(py=lambda c: "mcrecon.Session('box', {'radius': 10**30})"),
        mentions=["radius", str(10**30)], note="bare RuntimeError 'Unable to cast Python instance' (issue 9)")
    add("non_numeric_parameter", param_fe("radius=abc", "", "{'radius': 'abc'}"), mentions=["radius", "abc"])
    add("nan_parameter", param_fe("radius=nan", "", "{'radius': float('nan')}"), mentions=["radius", "nan"])
    add("compression_bogus",
        dict(cli=cli_denoise("{inp}", "{out}", "--compression", "bogus"),
             oiio_write=oiio_write("{out}", "--attrib", "mcrecon:compression", "bogus")),
        mentions=["bogus"], note="accepted silently (issue 9)")
    add("output_extension_xyz", dict(cli=cli_denoise("{inp}", "{d}/out.xyz"), py=py_file("{inp}", "{d}/out.xyz")),
        mentions=["out.xyz"], note="writes EXR under .xyz (issue 9)")
    add("region_outside_image", dict(cli=cli_denoise("{inp}", "{out}", "--region", "100,100,200,200"),
                                     py=lambda c: "mcrecon.denoise('box', np.ones((12, 16, 3), np.float32), "
                                                  "roi=(100, 100, 200, 200))"),
        mentions=[("100,100,200,200", "(100, 100, 200, 200)", "roi")], note="accepted silently (issue 9)")
    add("region_empty", dict(cli=cli_denoise("{inp}", "{out}", "--region", "4,4,4,8"),
                             py=lambda c: "mcrecon.denoise('box', np.ones((12, 16, 3), np.float32), roi=(4, 4, 4, 8))"),
        mentions=[("4,4,4,8", "(4, 4, 4, 8)", "roi")])
    add("region_negative", dict(cli=cli_denoise("{inp}", "{out}", "--region", "-4,-4,8,8"),
                                py=lambda c: "mcrecon.denoise('box', np.ones((12, 16, 3), np.float32), roi=(-4, -4, 8, 8))"),
        mentions=[("-4,-4,8,8", "(-4, -4, 8, 8)", "roi")])
    add("threads_negative", dict(cli=cli_denoise("{inp}", "{out}", "--threads", "-1"),
                                 py=py_file("{inp}", threads="-1")),
        mentions=["threads", "-1"], note="threads=-1 accepted by Python (issue 9)")
    add("threads_100000_ok", dict(cli=cli_denoise("{inp}", "{out}", "--threads", "100000"),
                                  py=py_file("{inp}", threads="100000")),
        expect="ok", outputs=["out.exr"], same_as_threads0=True, note="unclamped TBB arena (issue 4)")
    add("threads_100000000_ok", dict(cli=cli_denoise("{inp}", "{out}", "--threads", "100000000"),
                                     py=py_file("{inp}", threads="100000000")),
        expect="ok", outputs=["out.exr"], same_as_threads0=True, note="std::bad_alloc (issue 4)")
    add("demo_spp_3", dict(cli=lambda c: ["demo", "--spp", "3", "--filters", "box", "--samples", c.samples,
                                          "--out", c.p("demo")]),
        build=b_demo, mentions=["spp", "3"], note="runs nothing, exit 0 (issue 9)")
    add("unknown_subcommand", dict(cli=lambda c: ["frobnicate", c.inp]), mentions=["frobnicate"],
        note="'A subcommand is required' (issue 9)")

    # ------------------------------------------------------------------ passes
    add("missing_colour_pass",
        dict(cli=cli_denoise("{d}/nocolour.exr"), oiio_read=oiio_read("{d}/nocolour.exr"), py=py_file("{d}/nocolour.exr")),
        build=lambda c: bf.write_exr(c.p("nocolour.exr"), bf.blender_pixels(1)[..., 7:10],
                                     ["ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"]),
        mentions=["nocolour.exr", "colour"])
    add("multipart_different_windows",
        dict(cli=cli_denoise("{d}/parts.exr"), oiio_read=oiio_read("{d}/parts.exr"), py=py_file("{d}/parts.exr")),
        build=b_multipart, mentions=["parts.exr"])
    add("loose_pass_missing",
        dict(cli=cli_denoise("{inp}", "{out}", "--pass", "normal={d}/nosuch_normal.exr", filt="bilateral"),
             oiio_read=lambda c: oiio_read("{inp}", "filter=bilateral&normal=" + c.p("nosuch_normal.exr"))(c),
             py=lambda c: py_file("{inp}", filt="bilateral", passes=repr({"normal": c.p("nosuch_normal.exr")}))(c)),
        mentions=["nosuch_normal.exr"])
    add("loose_pass_other_size",
        dict(cli=cli_denoise("{inp}", "{out}", "--pass", "normal={d}/small_normal.exr", filt="bilateral"),
             oiio_read=lambda c: oiio_read("{inp}", "filter=bilateral&normal=" + c.p("small_normal.exr"))(c),
             py=lambda c: py_file("{inp}", filt="bilateral", passes=repr({"normal": c.p("small_normal.exr")}))(c)),
        build=lambda c: bf.write_exr(c.p("small_normal.exr"), np.full((8, 8, 3), 0.5), ["R", "G", "B"]),
        mentions=["normal", ("small_normal.exr", "8x8", "8 x 8")])
    for filt in ("bilateral", "bmfr"):
        add("nan_inf_every_pass_%s_ok" % filt,
            dict(cli=cli_denoise("{d}/odd.exr", filt=filt), oiio_read=oiio_read("{d}/odd.exr", "filter=" + filt),
                 py=py_file("{d}/odd.exr", filt=filt)),
            build=b_pixels(nan_inf), expect="ok", outputs=["out.exr"])
    add("flt_max_demodulate_ok",
        dict(cli=cli_denoise("{d}/odd.exr", "{out}", "--set", "demodulate=true"),
             oiio_read=oiio_read("{d}/odd.exr", "filter=box&demodulate=true"),
             py=py_file("{d}/odd.exr", params="{'demodulate': True}")),
        build=b_pixels(flt_max), expect="ok", outputs=["out.exr"], nonzero=True, note="zeros (issue 10)")
    add("flt_max_bmfr_ok",
        dict(cli=cli_denoise("{d}/odd.exr", filt="bmfr"), oiio_read=oiio_read("{d}/odd.exr", "filter=bmfr"),
             py=py_file("{d}/odd.exr", filt="bmfr")),
        build=b_pixels(flt_max), expect="ok", outputs=["out.exr"], nonzero=True, note="zeros (issue 10)")

    # ------------------------------------------------------------------ Python arrays
    arr = "np.random.default_rng(0).random((12, 16, 3)).astype(np.float32)"
    add("py_complex_colour", dict(py=lambda c: "mcrecon.denoise('box', np.ones((12, 16, 3), np.complex64) * (1 + 2j))"),
        mentions=[("colour", "complex")], note="complex arrays accepted (issue 9)")
    add("py_1d_colour", dict(py=lambda c: "mcrecon.denoise('box', np.ones(48, np.float32))"), mentions=["colour"])
    add("py_feature_wrong_size",
        dict(py=lambda c: "mcrecon.denoise('bilateral', %s, normal=np.ones((6, 8, 3), np.float32))" % arr),
        mentions=["normal"])
    add("py_out_of_range_array", dict(py=lambda c: "mcrecon.denoise('box', %s, params={'radius': 1e20})" % arr),
        mentions=["radius", ("1e20", "1e+20")])

    # ------------------------------------------------------------------ plugin names
    add("plugin_malformed_query", dict(oiio_read=lambda c: [c.inp + ".mcrecon?radius", "-o", c.out]),
        mentions=["radius"])
    return C


CASES = _cases()


def cleanup(c):
    if getattr(c, "cleanup", None):
        c.cleanup()
    shutil.rmtree(c.d, ignore_errors=True)
