"""When the render's own output is not OpenEXR MultiLayer (PNG, JPEG, plain EXR, or F12 with no
file at all), the add-on writes the passes itself: a compositor File Output node named
"mcrecon passes" writes a multilayer EXR per frame into Blender's temp folder, with the same
channel names a multilayer render has ("ViewLayer.Combined.R", ..., "Composite.Combined.R"); the
render hooks delete each file once it is denoised. The node and the compositing switches are
changes recorded in changes.py."""
import os
import threading

import bpy

from . import changes

NODE = "mcrecon passes"


def needed(scene):
    return scene.mcrecon.enabled and scene.render.image_settings.file_format != "OPEN_EXR_MULTILAYER"


def node(scene):
    tree = scene.node_tree
    return tree.nodes.get(NODE) if tree is not None else None


def file_for(scene, frame):
    n = node(scene)
    return bpy.path.abspath(n.base_path) + "%04d.exr" % frame if n else None


def view_layer(scene):
    for vl in scene.view_layers:
        if vl.use:
            return vl
    return scene.view_layers[0]


def ensure(scene, log=print):
    """Adds, updates or removes the File Output node (main thread only: the tree is shared
    with the UI). Returns the node or None."""
    if threading.current_thread() is not threading.main_thread():
        return node(scene)
    n = node(scene)
    if not needed(scene):
        if n is not None:
            scene.node_tree.nodes.remove(n)
        return None
    why = "to write the passes: the output format is not OpenEXR MultiLayer"
    # use_nodes creates Render Layers -> Composite (the image is unchanged): nodes the add-on added.
    had = {n.name for n in scene.node_tree.nodes} if scene.node_tree is not None else set()
    if changes.set_value(scene, "", "use_nodes", True, why, log):
        for name in sorted({n.name for n in scene.node_tree.nodes} - had):
            changes.added_node(scene, name, "created with the compositing nodes", log)
    changes.set_value(scene, "render", "use_compositing", True, why, log)
    tree = scene.node_tree
    vl = view_layer(scene)
    rl = next((x for x in tree.nodes if x.bl_idname == "CompositorNodeRLayers" and x.layer == vl.name), None)
    if rl is None:
        rl = tree.nodes.new("CompositorNodeRLayers")
        rl.layer = vl.name
        rl.location = (-300, -400)
        changes.added_node(scene, rl.name, why, log)
    if n is None:
        n = tree.nodes.new("CompositorNodeOutputFile")
        n.name = n.label = NODE
        n.location = (300, -400)
        changes.added_node(scene, NODE, why, log)
    n.format.file_format = "OPEN_EXR_MULTILAYER"
    n.format.color_depth = "32"
    n.format.exr_codec = "ZIP"
    n.base_path = os.path.join(bpy.app.tempdir or "/tmp", "mcrecon_%s_" % bpy.path.clean_name(scene.name))
    n.layer_slots.clear()
    for out in rl.outputs:
        if out.enabled and out.name != "Alpha":  # Combined carries alpha
            n.layer_slots.new(vl.name + "." + ("Combined" if out.name == "Image" else out.name))
            tree.links.new(out, n.inputs[-1])
    comp = next((x for x in tree.nodes if x.bl_idname == "CompositorNodeComposite"), None)
    if comp is not None and comp.inputs["Image"].is_linked:
        n.layer_slots.new("Composite.Combined")
        tree.links.new(comp.inputs["Image"].links[0].from_socket, n.inputs[-1])
    return n
