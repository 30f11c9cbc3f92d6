"""The page of `mcrecon report`: OUT_DIR/results.json -> OUT_DIR/plots/*.png + OUT_DIR/report.html.

    /usr/bin/python3 report/render_report.py OUT_DIR
    import render_report; render_report.render(OUT_DIR)

The page is one self-contained file (every image a base64 data: URI, CSS inline, no network) so it
can be mailed. Every numeric table cell carries its exact JSON value in `data-value` (json.dumps of
the value: the float's repr, or "null") with `data-scene`, `data-run`/`data-level` and `data-key`,
so a test can check page == JSON. Files are written to a temp name in the same folder and renamed.
Progress goes to stderr. The schema is in report/README.md.
"""
import base64
import html
import io
import json
import math
import os
import re
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")  # no display, no GUI toolkit
matplotlib.rcParams["text.usetex"] = False
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

FORMAT = "mcrecon-report-1"
SPLIT_TEXT = {"tune": "settings chosen on this scene", "report": "held out", "user": "user render"}
TIMING_TEXT = {
    "in-process": "time: in process (the filter call only)",
    "command": "time: as a command (wall clock from spawn to exit, reading and writing included)",
}
# Numeric columns of the runs table: (json key, heading).
RUN_COLUMNS = [("seconds", "seconds"), ("filter_seconds", "filter seconds"),
               ("peak_memory_mb", "peak memory MB"), ("relmse", "relMSE"), ("psnr", "PSNR"),
               ("ssim", "SSIM"), ("temporal_error", "temporal error"),
               ("worth_x_samples", "worth N x samples")]
LEVEL_COLUMNS = [("spp", "spp"), ("relmse", "relMSE"), ("psnr", "PSNR"), ("ssim", "SSIM"),
                 ("temporal_error", "temporal error")]
FIT_COLUMNS = [("slope", "slope (log time / log pixels)"), ("seconds_per_megapixel", "seconds per MP"),
               ("peak_memory_mb_per_megapixel", "peak memory MB per MP")]


class ReportError(Exception):
    """A report folder that cannot be rendered (missing or malformed results.json)."""


def log(msg):
    print("page: " + msg, file=sys.stderr, flush=True)


# ---------------------------------------------------------------- small helpers

def esc(s):
    return html.escape("" if s is None else str(s), quote=True)


def is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def fmt(v, suffix=""):
    """Visible text of a number: 4 significant digits; null or non-finite -> '-'."""
    if not is_num(v):
        return "-"
    if isinstance(v, int):
        return str(v) + suffix
    return ("%.4g" % v) + suffix


def data_value(v):
    """The exact JSON text of a value (float repr, int, or null)."""
    return json.dumps(v)


def num_cell(v, attrs, suffix=""):
    a = " ".join('%s="%s"' % (k, esc(x)) for k, x in attrs)
    return '<td class="num" %s data-value="%s">%s</td>' % (a, esc(data_value(v)), esc(fmt(v, suffix)))


def slug(s):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", str(s)) or "_"


def write_atomic(path, data):
    """Writes bytes to a temp file in the same folder, then renames it over `path`."""
    tmp = os.path.join(os.path.dirname(path), ".%s.tmp%d" % (os.path.basename(path), os.getpid()))
    try:
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def save_fig(fig, path):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    plt.close(fig)
    write_atomic(path, buf.getvalue())


class Images:
    """Reads PNGs of the report folder once and hands out data: URIs (<img> or a placeholder)."""

    def __init__(self, out_dir):
        self.out_dir = out_dir
        self.missing = []

    def uri(self, rel):
        if not rel:
            return None
        p = os.path.join(self.out_dir, rel)
        try:
            with open(p, "rb") as f:
                data = f.read()
        except OSError:
            self.missing.append(rel)
            log("warning: missing image %s" % p)
            return None
        return "data:image/png;base64," + base64.b64encode(data).decode("ascii")

    def img(self, rel, alt, cls=""):
        u = self.uri(rel)
        if u is None:
            return '<div class="missing">missing image<br>%s</div>' % esc(rel or alt)
        return '<img class="%s" src="%s" alt="%s">' % (esc(cls), u, esc(alt))


def read_float(path, warn):
    """An image file as (channel names, float32 H x W x C array), or None (a warning when `warn`)."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if inp is None:
        if warn:
            log("warning: cannot read %s: %s" % (path, oiio.geterror()))
        return None
    try:
        names = list(inp.spec().channelnames)
        px = inp.read_image(oiio.FLOAT)
    finally:
        inp.close()
    if px is None:
        return None
    px = np.asarray(px, dtype=np.float32)
    return names, (px[:, :, None] if px.ndim == 2 else px)


def read_png(path):
    """A PNG as float RGB in [0, 1] (for the crop locator thumbnail), or None."""
    got = read_float(path, False)
    if got is None:
        return None
    px = got[1]
    if px.shape[2] == 1:
        px = np.repeat(px, 3, axis=2)
    return np.clip(px[:, :, :3], 0.0, 1.0)


def read_error_map(path):
    """A run's error EXR: the 'Y' channel (else the first) as a float32 2-D array, or None."""
    got = read_float(path, True)
    if got is None:
        return None
    names, px = got
    return px[:, :, names.index("Y") if "Y" in names else 0]


# ---------------------------------------------------------------- plots

def mt(s):
    """Text for matplotlib as typed: a '$' in a name would start mathtext."""
    return str(s).replace("$", r"\$")


def run_label(r):
    if r.get("kind") == "auto":
        return "auto -> %s" % r["chosen"] if r.get("chosen") else "auto"
    return str(r.get("filter") or r.get("id"))


def filter_colours(runs):
    names = []
    for r in runs:
        f = r.get("filter") or r.get("id")
        if f not in names:
            names.append(f)
    cmap = plt.get_cmap("tab10" if len(names) <= 10 else "tab20")
    return {f: cmap(i % cmap.N) for i, f in enumerate(names)}


def place_labels(ax, items, fontsize=7):
    """Labels next to points, each at the first offset whose box misses the ones placed before
    (an estimate from the text length: enough to keep a dozen labels apart)."""
    fig = ax.figure
    fig.canvas.draw()
    to_px = ax.transData
    placed = []
    offsets = [(5, 4), (5, -11), (-5, 4), (-5, -11), (5, 14), (5, -21), (-5, 14), (-5, -21),
               (12, 24), (12, -31)]
    h = fontsize * 1.3 * fig.dpi / 72.0
    ax_box = ax.get_window_extent()
    for x, y, text in items:
        px, py = to_px.transform((x, y))
        w = len(text) * fontsize * 0.6 * fig.dpi / 72.0
        best = offsets[0]
        for dx, dy in offsets:
            ox, oy = dx * fig.dpi / 72.0, dy * fig.dpi / 72.0
            x0 = px + ox if dx >= 0 else px + ox - w
            box = (x0, py + oy, x0 + w, py + oy + h)
            inside = ax_box.x0 <= box[0] and box[2] <= ax_box.x1 and ax_box.y0 <= box[1] and box[3] <= ax_box.y1
            if inside and not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in placed):
                best = (dx, dy)
                placed.append(box)
                break
        else:
            best = (-5, 4) if px + w > ax_box.x1 else (5, 4)
            placed.append((px, py, px + w, py + h))
        ax.annotate(text, (x, y), xytext=best, textcoords="offset points", fontsize=fontsize,
                    ha="left" if best[0] >= 0 else "right", va="bottom", color="0.15")


# The second view of a command-timed scene: what the filter itself costs, without the process.
FILTER_TIME_TEXT = "time: mcrecon's own filter time (--timings: no start-up, reading or writing; peers have none)"


def pareto_plot(scene, key, path, xkey="seconds"):
    """Run time (log) against relMSE (log) or SSIM (linear); returns the runs left out.
    xkey "filter_seconds": mcrecon's own filter time of command-timed runs (peers have none)."""
    runs = scene.get("runs") or []
    log_y = key == "relmse"
    colours = filter_colours(runs)
    fig, ax = plt.subplots(figsize=(8.5, 5.2))
    left_out = []

    def ok(r):
        s, v = r.get(xkey), r.get(key)
        good = is_num(s) and s > 0 and is_num(v) and (v > 0 or not log_y)
        if not good:
            left_out.append(r.get("id"))
        return good

    shown = [r for r in runs if ok(r)]
    # Sweeps: hollow points joined in sweep order, one line per (filter, swept parameter).
    sweeps = {}
    for r in shown:
        if r.get("sweep"):
            sweeps.setdefault((r.get("filter"), r["sweep"].get("param")), []).append(r)
    for (f, param), rs in sweeps.items():
        rs.sort(key=lambda r: r["sweep"].get("value") if is_num(r["sweep"].get("value")) else 0)
        c = colours.get(f, "0.5")
        ax.plot([r[xkey] for r in rs], [r[key] for r in rs], "-", lw=0.7, color=c, zorder=2)
        ax.scatter([r[xkey] for r in rs], [r[key] for r in rs], s=28, facecolors="white",
                   edgecolors=[c], linewidths=1.1, zorder=3, label=mt("%s: sweep of %s" % (f, param)))
    marker = {"filter": "o", "auto": "*", "peer": "D"}
    size = {"filter": 40, "auto": 150, "peer": 45}
    labels = []
    for r in shown:
        if r.get("sweep"):
            continue
        kind = r.get("kind", "filter")
        c = colours.get(r.get("filter") or r.get("id"), "0.5")
        filled = r.get("default", True) or kind != "filter"
        ax.scatter([r[xkey]], [r[key]], marker=marker.get(kind, "o"), s=size.get(kind, 40),
                   facecolors=[c] if filled else "white", edgecolors="black" if filled else [c],
                   linewidths=0.6, zorder=4)
        if filled:
            labels.append((r[xkey], r[key], mt(run_label(r))))
    front = sorted((r for r in shown if r.get("pareto_" + key)), key=lambda r: r[xkey]) if xkey == "seconds" else []
    if front:
        ax.step([r[xkey] for r in front], [r[key] for r in front], where="post", color="0.2",
                lw=1.3, alpha=0.7, zorder=1)
    for lv in scene.get("levels") or []:
        v = lv.get(key)
        if is_num(v) and (v > 0 or not log_y):
            ax.axhline(v, ls="--", lw=0.8, color="0.45", zorder=0)
            ax.annotate(mt(lv.get("label", "")), (0.005, v), xycoords=("axes fraction", "data"),
                        xytext=(2, 2), textcoords="offset points", fontsize=7, color="0.3")
    ax.set_xscale("log")
    if log_y:
        ax.set_yscale("log")
    ax.set_xlabel("run time, seconds (log)" if xkey == "seconds" else "filter time, seconds (log)")
    ax.set_ylabel("relMSE (log, lower is better)" if log_y else "SSIM (higher is better)")
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    ax.set_title(mt("%s: %s against time\n%s" % (scene.get("id"), "relMSE" if log_y else "SSIM",
                                               TIMING_TEXT.get(scene.get("timing"), "time: %s" % scene.get("timing"))
                                               if xkey == "seconds" else FILTER_TIME_TEXT),
                 ), fontsize=10)
    place_labels(ax, labels)
    handles = [
        Line2D([], [], ls="", marker="o", mfc="0.6", mec="black", label="filter, default settings"),
        Line2D([], [], ls="", marker="o", mfc="white", mec="0.4", label="sweep point"),
        Line2D([], [], ls="", marker="*", ms=11, mfc="0.6", mec="black", label="auto"),
        Line2D([], [], ls="", marker="D", mfc="0.6", mec="black", label="peer"),
        Line2D([], [], color="0.2", lw=1.3, drawstyle="steps-post", label="Pareto front"),
        Line2D([], [], color="0.45", ls="--", lw=0.8, label="renders of the scene (spp)"),
    ]
    h2, l2 = ax.get_legend_handles_labels()
    ax.legend(handles=handles + h2, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if left_out:
        ax.text(0.99, 0.01, mt("not drawn (no value or not positive): " + ", ".join(map(str, left_out))),
                transform=ax.transAxes, ha="right", va="bottom", fontsize=6, color="0.4")
    save_fig(fig, path)
    return left_out


def error_maps_plot(scene, out_dir, path):
    """All of a scene's error maps on one shared log scale; returns the number drawn (0: no file)."""
    maps = []
    for r in scene.get("runs") or []:
        rel = (r.get("images") or {}).get("error")
        if rel:
            m = read_error_map(os.path.join(out_dir, rel))
            if m is not None:
                maps.append((run_label(r), r.get("relmse"), m))
    if not maps:
        return 0
    vals = np.concatenate([m[np.isfinite(m) & (m > 0)].ravel() for _, _, m in maps])
    if vals.size:
        vmax = float(np.percentile(vals, 99.9))
        vmin = max(1e-4, float(np.percentile(vals, 1)))
    else:
        vmin, vmax = 1e-4, 1.0
    if not vmin < vmax:
        vmin = vmax / 100.0 if vmax > 0 else 1e-4
        vmax = max(vmax, vmin * 100.0)
    cols = min(4, len(maps))
    rows = (len(maps) + cols - 1) // cols
    h, w = maps[0][2].shape
    pw = 3.2
    fig, axes = plt.subplots(rows, cols, figsize=(pw * cols + 1.0, pw * h / max(w, 1) * rows + 0.8),
                             squeeze=False, layout="constrained")
    cmap = plt.get_cmap("inferno").copy()
    cmap.set_bad("cyan")  # non-finite pixels stand out
    im = None
    for i, ax in enumerate(axes.ravel()):
        ax.set_axis_off()
        if i >= len(maps):
            continue
        name, relmse, m = maps[i]
        shown = np.where(np.isfinite(m), np.clip(m, vmin, vmax), np.nan)  # zeros clip to the bottom
        im = ax.imshow(shown, cmap=cmap, norm=LogNorm(vmin=vmin, vmax=vmax), interpolation="nearest")
        ax.set_title(mt("%s (relMSE %s)" % (name, fmt(relmse))), fontsize=8)
    cb = fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.9)
    cb.set_label("relative squared error per pixel (log)", fontsize=8)
    fig.suptitle(mt("%s: error maps, one log scale" % scene.get("id")), fontsize=10)
    save_fig(fig, path)
    return len(maps)


def per_frame_plot(scene, key, path):
    """Sequences: a per-frame metric of every run that has one (sweeps left out) and the levels."""
    fig, ax = plt.subplots(figsize=(8.5, 4.0))
    colours = filter_colours(scene.get("runs") or [])
    drawn = 0

    def series(pf):
        fr = pf.get("frame") or []
        vs = pf.get(key) or []
        return [f for f, v in zip(fr, vs)], [v if is_num(v) and (v > 0 or key != "relmse") else np.nan
                                               for f, v in zip(fr, vs)]

    for r in scene.get("runs") or []:
        if r.get("sweep") or not r.get("per_frame"):
            continue
        x, y = series(r["per_frame"])
        if x:
            ax.plot(x, y, marker={"auto": "*", "peer": "D"}.get(r.get("kind"), "o"), ms=4, lw=1,
                    color=colours.get(r.get("filter") or r.get("id")), label=mt(run_label(r)))
            drawn += 1
    for lv in scene.get("levels") or []:
        if lv.get("per_frame"):
            x, y = series(lv["per_frame"])
            if x:
                ax.plot(x, y, "--", lw=0.8, color="0.45", label=mt(lv.get("label")))
                drawn += 1
    if key == "relmse":
        ax.set_yscale("log")
    ax.set_xlabel("frame")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel({"relmse": "relMSE (log)", "temporal_error": "temporal error"}[key])
    ax.set_title(mt("%s: %s per frame (lower is better)" % (
        scene.get("id"), {"relmse": "relMSE", "temporal_error": "temporal error"}[key])), fontsize=10)
    ax.grid(True, lw=0.4, alpha=0.5)
    if drawn:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    save_fig(fig, path)
    return drawn


def crop_locator_plot(scene, out_dir, path):
    """The noisy frame with every crop (solid) and its 4:1 zoom region (dotted) drawn and numbered."""
    rel = (scene.get("images") or {}).get("noisy")
    img = read_png(os.path.join(out_dir, rel)) if rel else None
    if img is None:
        return False
    h, w = img.shape[:2]
    fig, ax = plt.subplots(figsize=(4.0, 4.0 * h / max(w, 1)))
    ax.imshow(img, interpolation="nearest")
    for i, c in enumerate(scene.get("crops") or []):
        ax.add_patch(Rectangle((c["x"] - 0.5, c["y"] - 0.5), c["w"], c["h"], fill=False, ec="lime", lw=1.5))
        z = c.get("zoom")
        if z:
            ax.add_patch(Rectangle((z["x"] - 0.5, z["y"] - 0.5), z["w"], z["h"], fill=False, ec="yellow",
                                   lw=1.0, ls=":"))
        ax.text(c["x"], c["y"] - 2, "crop %d" % i, color="lime", fontsize=7, va="bottom")
    ax.set_axis_off()
    ax.set_title("crop regions (green 1:1, yellow 4:1)", fontsize=8)
    save_fig(fig, path)
    return True


def scaling_plots(scaling, plots_dir):
    """Time and peak memory against pixels, log-log, one panel per input kind; returns file names."""
    rows = [r for r in scaling.get("rows") or [] if is_num(r.get("pixels")) and r["pixels"] > 0]
    if not rows:
        return []
    fits = {(f.get("filter"), f.get("input")): f for f in scaling.get("fits") or []}
    inputs = []
    for r in rows:
        if r.get("input") not in inputs:
            inputs.append(r.get("input"))
    out = []
    for key, ylabel, name in (("seconds", "seconds (log)", "scaling_time.png"),
                              ("peak_memory_mb", "peak memory MB (log)", "scaling_memory.png")):
        fig, axes = plt.subplots(1, len(inputs), figsize=(5.5 * len(inputs) + 1.5, 4.5), squeeze=False)
        for ax, inp in zip(axes[0], inputs):
            lines = {}
            for r in rows:
                if r.get("input") == inp and is_num(r.get(key)) and r[key] > 0:
                    lines.setdefault(r.get("filter"), []).append((r["pixels"], r[key]))
            for f, pts in lines.items():
                pts.sort()
                fit = fits.get((f, inp), {})
                lab = str(f)
                if key == "seconds" and is_num(fit.get("slope")):
                    lab += " (slope %s)" % fmt(fit["slope"])
                elif key == "peak_memory_mb" and is_num(fit.get("peak_memory_mb_per_megapixel")):
                    lab += " (%s MB/MP)" % fmt(fit["peak_memory_mb_per_megapixel"])
                ax.plot([p for p, _ in pts], [v for _, v in pts], marker="o", ms=3, lw=1, label=mt(lab))
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("pixels (log)")
            ax.set_ylabel(ylabel)
            ax.set_title(mt("%s input" % inp), fontsize=10)
            ax.grid(True, which="both", lw=0.3, alpha=0.5)
            if lines:
                ax.legend(fontsize=7, loc="upper left")
        fig.suptitle("%s against image size (%s threads)" % (
            "run time" if key == "seconds" else "peak memory", scaling.get("threads", "?")), fontsize=10)
        save_fig(fig, os.path.join(plots_dir, name))
        out.append(name)
    spp = spp_plot(scaling, plots_dir)
    if spp:
        out.append(spp)
    return out


def spp_plot(scaling, plots_dir):
    """Run time against samples per pixel (one scene per input kind at its rendered spp levels)."""
    rows = [r for r in scaling.get("spp_rows") or [] if is_num(r.get("spp")) and is_num(r.get("seconds"))
            and r["seconds"] > 0]
    if not rows:
        return None
    inputs = []
    for r in rows:
        if r.get("input") not in inputs:
            inputs.append(r.get("input"))
    fig, axes = plt.subplots(1, len(inputs), figsize=(5.5 * len(inputs) + 1.5, 4.5), squeeze=False)
    for ax, inp in zip(axes[0], inputs):
        lines = {}
        for r in rows:
            if r.get("input") == inp:
                lines.setdefault(r.get("filter"), []).append((r["spp"], r["seconds"]))
        for f, pts in lines.items():
            pts.sort()
            ax.plot([p for p, _ in pts], [v for _, v in pts], marker="o", ms=3, lw=1, label=mt(str(f)))
        sizes = {(r.get("width"), r.get("height")) for r in rows if r.get("input") == inp}
        scene = {r.get("scene") for r in rows if r.get("input") == inp}
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("samples per pixel (log)")
        ax.set_ylabel("seconds (log)")
        ax.set_title(mt("%s input: %s, %s" % (inp, ", ".join(sorted(map(str, scene))),
                                              ", ".join("%sx%s" % s for s in sorted(sizes)))), fontsize=10)
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("run time against samples per pixel (%s threads)" % scaling.get("threads", "?"), fontsize=10)
    name = "scaling_spp.png"
    save_fig(fig, os.path.join(plots_dir, name))
    return name


# ---------------------------------------------------------------- page

CSS = """
body{font-family:sans-serif;margin:1.5em auto;max-width:1400px;padding:0 1em;color:#222;line-height:1.4}
h1{font-size:1.6em}h2{font-size:1.3em;border-bottom:1px solid #bbb;padding-bottom:.2em;margin-top:2em}
h3{font-size:1.05em;margin-top:1.4em}
table{border-collapse:collapse;font-size:.85em;margin:.6em 0}
th,td{border:1px solid #bbb;padding:.2em .5em;vertical-align:top}th{background:#f0f0f0;text-align:left}
td.num{text-align:right;font-variant-numeric:tabular-nums}
.meta{color:#555;font-size:.9em}.plot{max-width:100%;height:auto;display:block;margin:.5em 0}
.tiles{display:flex;flex-wrap:wrap;gap:.5em;align-items:flex-start;margin:.4em 0}
.tile{text-align:center;font-size:.75em;max-width:200px}.tile img{display:block;margin:0 auto;border:1px solid #999}
img.px{image-rendering:pixelated}.tile{min-width:90px}img.thumb{width:200px;height:auto}
.missing{width:64px;height:64px;border:1px dashed #c00;color:#c00;font-size:.7em;display:flex;align-items:center}
.note{background:#f7f7f7;border-left:3px solid #999;padding:.5em 1em;font-size:.9em}
nav ul{columns:3;font-size:.9em}
"""


def tile(images, rel, label, cls):
    return '<div class="tile">%s<div>%s</div></div>' % (images.img(rel, label, cls), label)


def runs_table(scene):
    seq = (scene.get("frames") or 1) > 1
    cols = [c for c in RUN_COLUMNS if seq or c[0] != "temporal_error"]
    runs = list(scene.get("runs") or [])
    runs.sort(key=lambda r: (not is_num(r.get("relmse")), r.get("relmse") if is_num(r.get("relmse")) else 0))
    sid = scene.get("id")
    out = ['<table class="runs"><tr><th>filter</th><th>parameters</th><th>default?</th>']
    out += ["<th>%s</th>" % esc(h) for _, h in cols]
    out.append("<th>Pareto</th><th>notes</th></tr>")
    for r in runs:
        name = esc(run_label(r))
        if r.get("kind") == "peer":
            name += " (peer)"
        params = r.get("parameters") or "(defaults)"
        pareto = [n for k, n in (("pareto_relmse", "relMSE"), ("pareto_ssim", "SSIM")) if r.get(k)]
        out.append('<tr data-run="%s"><td>%s</td><td>%s</td><td>%s</td>' % (
            esc(r.get("id")), name, esc(params), "yes" if r.get("default") else "no"))
        for k, _ in cols:
            out.append(num_cell(r.get(k), [("data-scene", sid), ("data-run", r.get("id")), ("data-key", k)],
                                "x" if k == "worth_x_samples" else ""))
        out.append("<td>%s</td><td>%s</td></tr>" % (
            "&#9679; " + ", ".join(pareto) if pareto else "", esc("; ".join(map(str, r.get("notes") or [])))))
    out.append("</table>")
    return "".join(out)


def levels_table(scene):
    seq = (scene.get("frames") or 1) > 1
    cols = [c for c in LEVEL_COLUMNS if seq or c[0] != "temporal_error"]
    out = ['<table class="levels"><tr><th>render</th>'] + ["<th>%s</th>" % esc(h) for _, h in cols] + ["</tr>"]
    for i, lv in enumerate(scene.get("levels") or []):
        out.append("<tr><td>%s</td>" % esc(lv.get("label")))
        for k, _ in cols:
            out.append(num_cell(lv.get(k), [("data-scene", scene.get("id")), ("data-level", i), ("data-key", k)]))
        out.append("</tr>")
    out.append("</table>")
    return "".join(out)


def input_level(scene):
    for lv in scene.get("levels") or []:
        if lv.get("is_input"):
            return lv
    return {}


def crops_html(scene, images, locator):
    crops = scene.get("crops") or []
    if not crops:
        return ""
    runs = [r for r in scene.get("runs") or [] if (r.get("images") or {}).get("crops_1x")]
    noisy_lab = "noisy %s spp<br>relMSE %s" % (esc(fmt(scene.get("spp"))), esc(fmt(input_level(scene).get("relmse"))))
    ref_lab = "reference %s spp" % esc(fmt(scene.get("reference_spp")))
    out = ["<h3>Crops</h3>"]
    if locator:
        out.append('<div class="tiles"><div class="tile" style="max-width:420px">%s</div></div>' % images.img(
            locator, "crop regions", "plot"))
    for i, c in enumerate(crops):
        z = c.get("zoom") or {}
        out.append('<p class="meta">crop %d: x %s, y %s, %s&times;%s pixels; '
                   '4:1 zoom of x %s, y %s, %s&times;%s</p>' % (
            i, c.get("x"), c.get("y"), c.get("w"), c.get("h"), z.get("x"), z.get("y"), z.get("w"), z.get("h")))
        for scale, key in (("1:1", "1x"), ("4:1", "4x")):
            row = [tile(images, c.get("noisy_" + key), noisy_lab, "px")]
            for r in runs:
                lst = r["images"].get("crops_" + key) or []
                rel = lst[i] if i < len(lst) else None
                row.append(tile(images, rel, "%s<br>relMSE %s" % (esc(run_label(r)), esc(fmt(r.get("relmse")))), "px"))
            row.append(tile(images, c.get("reference_" + key), ref_lab, "px"))
            out.append('<div class="meta">%s</div><div class="tiles">%s</div>' % (scale, "".join(row)))
    return "".join(out)


def scene_html(scene, idx, n, out_dir, plots_dir, images):
    sid = scene.get("id", "scene%d" % idx)
    log("scene %d/%d %s" % (idx + 1, n, sid))
    base = slug(sid)
    split = scene.get("split")
    timing = scene.get("timing")
    out = ['<section id="scene-%s"><h2>%s</h2>' % (esc(base), esc(sid))]
    out.append('<p class="meta">%s; %s&times;%s; %s frame%s; input %s spp; reference %s spp; %s; %s</p>' % (
        esc(scene.get("kind")), esc(scene.get("width")), esc(scene.get("height")), esc(scene.get("frames")),
        "" if scene.get("frames") == 1 else "s", esc(fmt(scene.get("spp"))), esc(fmt(scene.get("reference_spp"))),
        esc(SPLIT_TEXT.get(split, "split: %s" % split)), esc(TIMING_TEXT.get(timing, "time: %s" % timing))))
    for key in ("relmse", "ssim"):
        name = "%s_pareto_%s.png" % (base, key)
        pareto_plot(scene, key, os.path.join(plots_dir, name))
        out.append(images.img("plots/" + name, "%s against time" % key, "plot"))
    if timing == "command":  # process times are mostly start-up on small frames: the filters' own too
        name = "%s_filter_time_relmse.png" % base
        pareto_plot(scene, "relmse", os.path.join(plots_dir, name), xkey="filter_seconds")
        out.append(images.img("plots/" + name, "relmse against filter time", "plot"))
    out.append("<h3>Runs (sorted by relMSE)</h3>" + runs_table(scene))
    out.append("<h3>Renders of the scene</h3>" + levels_table(scene))
    locator = "%s_crops.png" % base
    has_loc = crop_locator_plot(scene, out_dir, os.path.join(plots_dir, locator)) if scene.get("crops") else False
    out.append(crops_html(scene, images, "plots/" + locator if has_loc else None))
    name = "%s_errors.png" % base
    if error_maps_plot(scene, out_dir, os.path.join(plots_dir, name)):
        out.append("<h3>Error maps</h3>" + images.img("plots/" + name, "error maps", "plot"))
    if (scene.get("frames") or 1) > 1:
        out.append("<h3>Per frame</h3>")
        for key in ("temporal_error", "relmse"):
            name = "%s_frames_%s.png" % (base, key)
            if per_frame_plot(scene, key, os.path.join(plots_dir, name)):
                out.append(images.img("plots/" + name, "%s per frame" % key, "plot"))
    full = [(run_label(r), r["images"]["full"], r.get("relmse")) for r in scene.get("runs") or []
            if (r.get("images") or {}).get("full")]
    if full:
        imgs = scene.get("images") or {}
        row = [tile(images, imgs.get("noisy"), "noisy", "thumb")] if imgs.get("noisy") else []
        row += [tile(images, rel, "%s<br>relMSE %s" % (esc(lab), esc(fmt(v))), "thumb") for lab, rel, v in full]
        if imgs.get("reference"):
            row.append(tile(images, imgs["reference"], "reference", "thumb"))
        out.append('<h3>Full frames</h3><div class="tiles">%s</div>' % "".join(row))
    out.append("</section>")
    return "".join(out)


def scaling_html(scaling, plots_dir, images):
    out = ['<section id="scaling"><h2>Scaling</h2>']
    for key in ("method", "spp_method"):
        if scaling.get(key):
            out.append('<p class="meta">%s</p>' % esc(scaling[key]))
    names = scaling_plots(scaling, plots_dir)
    if not names:
        out.append("<p>No scaling measurements.</p>")
    for name in names:
        out.append(images.img("plots/" + name, name, "plot"))
    fits = scaling.get("fits") or []
    if fits:
        out.append('<table class="fits"><tr><th>filter</th><th>input</th>%s</tr>' % "".join(
            "<th>%s</th>" % esc(h) for _, h in FIT_COLUMNS))
        for i, f in enumerate(fits):
            out.append("<tr><td>%s</td><td>%s</td>" % (esc(f.get("filter")), esc(f.get("input"))))
            for k, _ in FIT_COLUMNS:
                out.append(num_cell(f.get(k), [("data-fit", i), ("data-key", k)]))
            out.append("</tr>")
        out.append("</table>")
    out.append("</section>")
    return "".join(out)


HEAD_SCRIPT = ("<script>window.reportErrors=0;"
               "window.addEventListener('error',function(){window.reportErrors++;},true);</script>")
# After load: every <img> decoded? Written where a headless browser's --dump-dom can read it.
TAIL_SCRIPT = """<script>
window.addEventListener('load',function(){
  var imgs=document.getElementsByTagName('img'),broken=0;
  for(var i=0;i<imgs.length;i++){if(!(imgs[i].complete&&imgs[i].naturalWidth>0))broken++;}
  var s=document.getElementById('report-status');
  s.setAttribute('data-errors',String(window.reportErrors));
  s.setAttribute('data-images',String(imgs.length));
  s.setAttribute('data-broken',String(broken));
  s.textContent=(window.reportErrors===0&&broken===0)?'ok':
    ('page check: '+window.reportErrors+' errors, '+broken+' of '+imgs.length+' images broken');
});
</script>"""


def load_results(out_dir):
    path = os.path.join(out_dir, "results.json")
    try:
        with open(path, "r", encoding="utf-8") as f:
            res = json.load(f)
    except OSError as e:
        raise ReportError("cannot read %s: %s" % (path, e.strerror or e))
    except ValueError as e:
        raise ReportError("%s is not valid JSON: %s" % (path, e))
    if not isinstance(res, dict) or not isinstance(res.get("scenes", []), list):
        raise ReportError("%s: not a report (no 'scenes' list)" % path)
    if res.get("format") != FORMAT:
        log("warning: %s has format %r, this page reads %r" % (path, res.get("format"), FORMAT))
    return res


def render(out_dir):
    """Renders OUT_DIR/results.json into OUT_DIR/plots/*.png and OUT_DIR/report.html; returns the page's path."""
    res = load_results(out_dir)
    plots_dir = os.path.join(out_dir, "plots")
    os.makedirs(plots_dir, exist_ok=True)
    images = Images(out_dir)
    scenes = res.get("scenes") or []
    m = res.get("machine") or {}
    body = []
    for i, sc in enumerate(scenes):
        body.append(scene_html(sc, i, len(scenes), out_dir, plots_dir, images))
    scaling = res.get("scaling")
    if scaling:
        log("scaling")
        body.append(scaling_html(scaling, plots_dir, images))
    toc = ['<nav><h2>Contents</h2><ul>']
    toc += ['<li><a href="#scene-%s">%s</a> <span class="meta">(%s, %s)</span></li>' % (
        esc(slug(sc.get("id", "scene%d" % i))), esc(sc.get("id")), esc(sc.get("kind")),
        esc(SPLIT_TEXT.get(sc.get("split"), sc.get("split")))) for i, sc in enumerate(scenes)]
    if scaling:
        toc.append('<li><a href="#scaling">Scaling</a></li>')
    toc.append("</ul></nav>")
    machine = "; ".join("%s: %s" % (k.replace("_", " "), v) for k, v in m.items())
    head = [
        "<!DOCTYPE html>",
        '<html lang="en"><head>' + HEAD_SCRIPT,
        '<meta charset="utf-8"><title>mcrecon report</title><style>%s</style></head><body>' % CSS,
        "<h1>mcrecon report: run time against error</h1>",
        '<p class="meta">created %s by mcrecon %s<br>machine: %s</p>' % (
            esc(res.get("created")), esc(res.get("mcrecon")), esc(machine)),
        '<p class="meta">timing: %s<br>memory: %s</p>' % (esc(res.get("timing_note")), esc(res.get("memory_note"))),
        '<div class="note"><b>How to read this.</b> Each scene has two plots of run time (x, log seconds) '
        "against error: relMSE (y, log; lower-left is better) and SSIM (y; upper-left is better). Filled "
        "points are filters at their default settings, hollow points joined by a thin line are a sweep of "
        "one parameter, the star is <code>auto</code>, diamonds are peers (other denoisers, timed as "
        "commands). The step line is the Pareto front: no run is both faster and better than a point on "
        "it. Dashed horizontal lines are the noisy input and renders of the same scene with more samples. "
        "&ldquo;Worth N&times; samples&rdquo;: the sample count at which the noisy render would reach the "
        "run's relMSE (by a power-law fit through the renders' relMSE against spp), over the input's "
        "sample count; 3.2x means the filter did what 3.2 times the samples would. Table numbers are "
        "rounded to 4 significant digits; the exact values are in results.json.</div>",
        '<div id="report-status" class="meta" data-errors="-1" data-images="-1" data-broken="-1">'
        "page check did not run</div>",
    ]
    page = "\n".join(head + toc + body + [TAIL_SCRIPT, "</body></html>"])
    path = os.path.join(out_dir, "report.html")
    write_atomic(path, page.encode("utf-8"))
    log("wrote %s (%d scenes, %.1f MB%s)" % (path, len(scenes), len(page) / 1e6,
                                               ", %d missing images" % len(images.missing) if images.missing else ""))
    return path


def main(argv):
    if len(argv) != 2:
        print("usage: render_report.py OUT_DIR  (a folder written by `mcrecon report`)", file=sys.stderr)
        return 2
    try:
        render(argv[1])
    except ReportError as e:
        print("render_report: %s" % e, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
