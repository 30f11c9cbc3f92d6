"""What the add-on changed in a scene, and putting it back.

Every setting the add-on changes (a pass toggle, Cycles' denoiser, compositing) goes through
set_value(), which records the user's value once in the scene's "mcrecon_changes" ID property (a
JSON list, saved with the .blend, kept when the add-on is disabled) and says what it did.
restore() puts every recorded value back and removes the nodes the add-on added: on disabling
the add-on or its switch. A setting the user had as the add-on wants is never recorded."""
import json

import bpy

KEY = "mcrecon_changes"


def _load(scene):
    try:
        return json.loads(scene.get(KEY, "[]"))
    except ValueError:
        return []


def _save(scene, records):
    if records:
        scene[KEY] = json.dumps(records)
    elif KEY in scene:
        del scene[KEY]


def layer_path(view_layer, owner=""):
    """The scene-relative path of a view layer (or its `owner`, e.g. "cycles")."""
    path = 'view_layers["%s"]' % bpy.utils.escape_identifier(view_layer.name)
    return path + "." + owner if owner else path


def _resolve(scene, owner):
    if not owner:
        return scene
    try:
        return scene.path_resolve(owner)
    except ValueError:  # the view layer was renamed or removed
        return None


def label(owner, attr):
    return (owner + "." if owner else "scene.") + attr


def set_value(scene, owner, attr, value, why, log=print):
    """Sets owner.attr (owner: a path from the scene, "" for the scene) to value, recording the
    user's value the first time. Returns True when it changed something."""
    obj = _resolve(scene, owner)
    if obj is None or not hasattr(obj, attr) or getattr(obj, attr) == value:
        return False
    records = _load(scene)
    if not any(r.get("owner") == owner and r.get("attr") == attr for r in records):
        records.append({"owner": owner, "attr": attr, "was": getattr(obj, attr), "why": why})
    setattr(obj, attr, value)
    _save(scene, records)
    log(f"mcrecon: set {label(owner, attr)} = {value!r} ({why}); turning mcrecon off puts it back")
    return True


def changed(scene, owner, attr):
    return any(r.get("owner") == owner and r.get("attr") == attr for r in _load(scene))


def revert(scene, owner, attr, log=print):
    """Puts one recorded setting back (the add-on no longer needs it)."""
    records = _load(scene)
    keep = []
    for r in records:
        if r.get("owner") == owner and r.get("attr") == attr:
            obj = _resolve(scene, owner)
            if obj is not None:
                setattr(obj, attr, r["was"])
                log(f"mcrecon: set {label(owner, attr)} back to {r['was']!r} (no longer needed)")
        else:
            keep.append(r)
    _save(scene, keep)


def added_node(scene, name, why, log=print):
    records = _load(scene)
    if not any(r.get("node") == name for r in records):
        records.append({"node": name, "why": why})
        _save(scene, records)
    log(f"mcrecon: added compositor node '{name}' ({why}); turning mcrecon off removes it")


def restore(scene, log=print):
    """Every recorded setting back to the user's value, latest first; the added nodes removed."""
    records = _load(scene)
    for r in reversed(records):
        if "node" in r:
            tree = scene.node_tree
            n = tree.nodes.get(r["node"]) if tree is not None else None
            if n is not None:
                tree.nodes.remove(n)
                log(f"mcrecon: removed compositor node '{r['node']}'")
            continue
        obj = _resolve(scene, r["owner"])
        if obj is not None and hasattr(obj, r["attr"]):
            setattr(obj, r["attr"], r["was"])
            log(f"mcrecon: set {label(r['owner'], r['attr'])} back to {r['was']!r}")
    _save(scene, [])
    return len(records)


def listing(scene):
    """One line per change in force, for the panel."""
    out = []
    for r in _load(scene):
        if "node" in r:
            out.append(f"Added node '{r['node']}' ({r['why']})")
            continue
        obj = _resolve(scene, r["owner"])
        now = getattr(obj, r["attr"], "?") if obj is not None else "?"
        out.append(f"{label(r['owner'], r['attr'])}: {r['was']!r} -> {now!r} ({r['why']})")
    return out
