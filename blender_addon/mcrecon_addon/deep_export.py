"""Per-sample export for `sweep` (issue 17): K sub-renders at 1 spp written as one deep EXR in
the per-sample convention (README).

Facts it rests on (../shared/notes/blender.md): K renders at 1 spp with the same seed and
cycles.sample_offset = k are the K samples of the stratified K-spp render; with
sample_offset > 0 the Depth pass is invalid, so each sample's depth comes from a shader AOV
("mcrecon_z": Camera Data's View Z Depth into an AOV Output in every node material; the world
leaves it 0, the convention's background); a pixel filter of 0.01 px (Cycles' minimum) puts every
sample at the pixel centre (dx = dy = 0.5). With motion blur on, the Vector pass is dropped:
motion comes from one more 1-spp render with motion blur off, per pixel (the surface seen at the
frame's centre), times the shutter, and every sample of the pixel gets it (mx, my: pixels over
the shutter, x right, y up). The camera for the circle of confusion goes into the header
(mcrecon:lens_mm, fstop, focus_distance, sensor_width_mm) when depth of field is on.

Every setting it changes, every node and AOV it adds, is put back; the sub-renders' files are
deleted as they are read."""
import os

import bpy

from . import native, sub_render

AOV = "mcrecon_z"
NODE_CAMERA = "mcrecon depth (Camera Data)"
NODE_AOV = "mcrecon depth (AOV)"


def camera_attributes(scene):
    """The header's camera, or {} when the camera has no depth of field."""
    cam_obj = scene.camera
    cam = cam_obj.data
    if cam.type != "PERSP" or not cam.dof.use_dof:
        return {}
    focus = cam.dof.focus_distance
    if cam.dof.focus_object is not None:  # planar distance along the view axis
        axis = cam_obj.matrix_world.to_3x3() @ (0.0, 0.0, -1.0)
        focus = (cam.dof.focus_object.matrix_world.translation - cam_obj.matrix_world.translation).dot(axis)
    r = scene.render
    w, h = r.resolution_x * r.pixel_aspect_x, r.resolution_y * r.pixel_aspect_y
    # The sensor size that spans the image width (Blender's sensor fit).
    if cam.sensor_fit == "VERTICAL" or (cam.sensor_fit == "AUTO" and h > w):
        size = cam.sensor_height if cam.sensor_fit == "VERTICAL" else cam.sensor_width
        sensor_w = size * w / h
    else:
        sensor_w = cam.sensor_width
    return {"mcrecon:lens_mm": float(cam.lens), "mcrecon:fstop": float(cam.dof.aperture_fstop),
            "mcrecon:focus_distance": float(focus), "mcrecon:sensor_width_mm": float(sensor_w)}


def _depth_aov(scene, layer, undo, log):
    """The AOV on the view layer and its nodes in every node material the layer renders."""
    if layer.aovs.get(AOV) is None:
        aov = layer.aovs.add()
        aov.name, aov.type = AOV, "VALUE"

        def remove_aov():  # no remove() on the collection in 3.4: the operator removes the active AOV
            i = layer.aovs.find(AOV)
            if i >= 0:
                layer.active_aov_index = i
                with bpy.context.temp_override(scene=scene, view_layer=layer):
                    bpy.ops.scene.view_layer_remove_aov()
        undo.add(remove_aov)
    without = []
    materials = {slot.material for obj in scene.objects if obj.type in {"MESH", "CURVE", "SURFACE", "META", "FONT"}
                 for slot in obj.material_slots if slot.material is not None}
    for obj in scene.objects:
        if obj.type == "MESH" and not any(s.material for s in obj.material_slots):
            without.append(obj.name)
    for mat in materials:
        if not mat.use_nodes or mat.node_tree is None:
            without.append(mat.name)
            continue
        tree = mat.node_tree
        cam = tree.nodes.new("ShaderNodeCameraData")
        cam.name = cam.label = NODE_CAMERA
        out = tree.nodes.new("ShaderNodeOutputAOV")
        out.name = AOV  # Blender 3.4: an AOV Output node's name is the AOV it writes
        out.label = NODE_AOV
        tree.links.new(cam.outputs["View Z Depth"], out.inputs["Value"])

        def remove_nodes(tree=tree, nodes=(cam, out)):
            for n in nodes:
                tree.nodes.remove(n)
        undo.add(remove_nodes)
    if without:
        log("objects or materials without shader nodes write no per-sample depth (read as background): "
            + ", ".join(sorted(without)[:10]) + (" ..." if len(without) > 10 else ""))


def _read(path, layer):
    """{channel name without the layer prefix: (h, w) float32} from a multilayer EXR."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError(f"cannot read the sub-render '{path}': {oiio.geterror()}")
    try:
        names = list(inp.spec().channelnames)
        px = inp.read_image(0, 0, 0, len(names), "float")
    finally:
        inp.close()
    prefix = layer + "."
    return {n[len(prefix):]: px[:, :, i] for i, n in enumerate(names) if n.startswith(prefix)}


def _channel(chans, *candidates):
    for c in candidates:
        if c in chans:
            return chans[c]
    raise RuntimeError(f"the sub-render has none of {candidates}; it has {sorted(chans)}")


def export(scene, filepath, samples, progress=None, log=print):
    """Renders `samples` sub-renders of the current frame and writes the deep EXR `filepath`.
    Returns {"samples", "width", "height", "camera", "motion"}. Raises on any failure; the
    scene is put back in every case."""
    import numpy as np
    mc = native.get()
    if scene.camera is None:
        raise ValueError("the scene has no camera")
    if samples < 1:
        raise ValueError(f"samples must be at least 1 (got {samples})")
    filepath = bpy.path.abspath(filepath)
    mc.check_outputs([filepath], [])
    if not filepath.lower().endswith(".exr"):
        raise ValueError(f"'{filepath}': the per-sample file is an OpenEXR (.exr)")
    r, cy = scene.render, scene.cycles
    with sub_render.job(scene, "export_deep", 1) as (undo, layer, tmpdir):
        undo.set(cy, "filter_width", 0.01)
        undo.keep(r, "use_motion_blur")
        _depth_aov(scene, layer, undo, log)
        w, h = int(r.resolution_x * r.resolution_percentage / 100), int(r.resolution_y * r.resolution_percentage / 100)
        motion = None
        total = samples + (1 if r.use_motion_blur else 0)
        if r.use_motion_blur:
            shutter = r.motion_blur_shutter
            r.use_motion_blur = False
            cy.sample_offset = 0
            undo.set(layer, "use_pass_vector", True)
            r.filepath = os.path.join(tmpdir, "motion")
            bpy.ops.render.render(write_still=True, layer=layer.name)
            path = os.path.join(tmpdir, "motion.exr")
            vec = _read(path, layer.name)
            os.remove(path)
            # XY and ZW: the motion over the frame before and the frame after, in pixels (the
            # same sign for a steady motion, verified on a keyed object): their mean is the
            # motion per frame; times the shutter (in frames), the blur length.
            before = np.stack([_channel(vec, "Vector.X"), _channel(vec, "Vector.Y")])
            after = np.stack([_channel(vec, "Vector.Z"), _channel(vec, "Vector.W")])
            motion = (before + after) * 0.5 * shutter
            r.use_motion_blur = True
            if progress:
                progress(1, total)
        rgb = np.zeros((samples, 3, h, w), np.float32)
        z = np.zeros((samples, h, w), np.float32)
        for k in range(samples):
            cy.sample_offset = k
            r.filepath = os.path.join(tmpdir, "s%05d" % k)
            bpy.ops.render.render(write_still=True, layer=layer.name)
            path = r.filepath + ".exr"
            chans = _read(path, layer.name)
            os.remove(path)
            for c, n in enumerate("RGB"):
                rgb[k, c] = _channel(chans, "Combined." + n)
            z[k] = _channel(chans, AOV + ".X", AOV + ".V", AOV + ".Value", AOV)
            done = k + 1 + (1 if motion is not None else 0)
            log(f"export_deep: sub-render {k + 1}/{samples} (sample_offset {k})")
            if progress:
                progress(done, total)
        channels = {"R": rgb[:, 0], "G": rgb[:, 1], "B": rgb[:, 2], "Z": z,
                    "dx": np.full_like(z, 0.5), "dy": np.full_like(z, 0.5)}
        if motion is not None:
            channels["mx"] = np.broadcast_to(motion[0], z.shape).copy()
            channels["my"] = np.broadcast_to(motion[1], z.shape).copy()
        camera = camera_attributes(scene)
        attributes = dict(camera)
        attributes["mcrecon:samples"] = str(samples)
        attributes["mcrecon:seed"] = str(cy.seed)
        attributes["mcrecon:frame"] = str(scene.frame_current)
        mc.write_deep(filepath, channels, attributes)
        log(f"export_deep: {filepath}: {w}x{h}, {samples} samples per pixel"
            + (", camera for the circle of confusion" if camera else ", no depth of field")
            + (", motion" if motion is not None else ""))
        return {"samples": samples, "width": w, "height": h, "camera": camera, "motion": motion is not None}
