"""How the panel shows a filter's parameters: Title Case labels, plain tooltips with the range,
small integer choices as menus, and the group (sub-panel) of each parameter. Pure functions (no
bpy): tests/python/test_output_guard.py checks them from plain Python."""
import re

# Sub-panels, in the order drawn; a parameter not named below is Advanced. "components" is the
# "Denoise Light Passes" checkbox of the main panel.
MAIN = ("radius", "sigma", "spatial_sigma", "kernel_size", "iterations", "epsilon", "min_radius", "max_radius",
        "block_size", "sample_fraction", "converged", "min_gain")
FOVEATION = ("foveated", "gaze_x", "gaze_y", "inner_radius", "outer_radius")
FIREFLIES = ("firefly_k", "firefly_radius", "clamp", "outlier_k", "outlier_radius", "sample_limit_k",
             "sample_limit_radius", "sample_limit_history")
FEATURES = ("guide", "colour_weight", "colour_sigma_decay", "demodulate", "albedo_demodulation", "albedo_floor",
            "albedo_prefilter", "albedo_prefilter_position", "sigma_c", "sigma_n", "sigma_sp", "sigma_sn",
            "features", "position_test", "position_threshold", "normal_threshold")
HIDDEN = ("components",)
GROUPS = ("main", "features", "fireflies", "foveation", "advanced")


def group_of(name):
    if name in HIDDEN:
        return None
    if name in MAIN:
        return "main"
    if name in FOVEATION or name.endswith("_outer"):
        return "foveation"
    if name in FIREFLIES:
        return "fireflies"
    if name in FEATURES or name.startswith("use_") or name.endswith("_sigma"):
        return "features"
    return "advanced"


# Words kept as they are written (units, acronyms) when a name becomes a label.
_WORDS = {"taa": "TAA", "k": "K", "x": "X", "y": "Y", "sp": "SP", "sn": "SN", "n": "N", "c": "C", "p": "P"}


def label(name):
    """'spatial_sigma_outer' -> 'Spatial Sigma Outer'; 'taa_alpha' -> 'TAA Alpha'."""
    return " ".join(_WORDS.get(w, w.capitalize()) for w in name.split("_"))


def _number(v, kind):
    if kind == "int":
        return str(int(v))
    text = ("%.6g" % v)
    return text


def tooltip(spec):
    """The parameter's help with its range and default in plain words."""
    t, text = spec["type"], spec["help"].rstrip(". ")
    text = text[:1].upper() + text[1:]
    if t in ("int", "float"):
        lo, hi = spec["min"], spec["max"]
        rng = "at least %s" % _number(lo, t) if hi >= 1e30 or hi >= 2**31 - 1 else \
              "%s to %s" % (_number(lo, t), _number(hi, t))
        return f"{text}. Range {rng}, default {_number(spec['default'], t)}"
    if t == "enum":
        return f"{text}. Default {spec['default']}"
    return f"{text}. Default {'on' if spec['default'] else 'off'}"


def int_choices(spec):
    """An integer with at most four values whose help names each ('0 = weighted mean; 1 = ...')
    as menu items [(value, label, description)]; None otherwise."""
    if spec["type"] != "int" or spec["max"] - spec["min"] > 3:
        return None
    items = []
    for v in range(int(spec["min"]), int(spec["max"]) + 1):
        m = re.search(r"(?:^|[;,(]\s*)%d\s*=\s*([^;,)]+)" % v, spec["help"])
        if not m:
            return None
        what = m.group(1).strip()
        short = what.split("(")[0].strip()
        if len(short) > 32:
            short = short[:32].rsplit(" ", 1)[0]
        items.append((str(v), short[:1].upper() + short[1:], what))
    return items


FILTER_LABELS = {"auto": "Auto (Chooses per Render)", "box": "Box", "gaussian": "Gaussian",
                 "bilateral": "Cross-Bilateral", "atrous": "Edge-Avoiding A-Trous", "guided": "Guided",
                 "pwaf": "Point-Wise Adaptive (PWAF)", "bmfr": "BMFR (Animations)"}


def filter_label(name):
    return FILTER_LABELS.get(name, label(name))


def wrap(text, width=60):
    """Lines of at most about `width` characters, broken at spaces (a panel label does not wrap)."""
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = (line + " " + word) if line else word
    if line:
        lines.append(line)
    return lines
