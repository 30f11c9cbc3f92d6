"""mcrecon for Blender: denoise Cycles renders with the mcrecon filters after every render.

Properties live under scene.mcrecon (generated from the filters' parameter tables), the panel is
in Render properties > mcrecon, the handlers run the chosen filter on the multilayer EXR each
render writes, and the operator mcrecon.denoise_files re-denoises saved EXR sequences.
"""

bl_info = {
    "name": "mcrecon denoiser",
    "author": "mcrecon developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > mcrecon",
    "description": "Reconstruct clean images from noisy Cycles renders (box, bilateral, pwaf, bmfr, ...)",
    "category": "Render",
}

from . import native, properties, passes, render_hooks, operators, ui, changes  # noqa: E402

_modules = (properties, operators, ui, render_hooks)


def register():
    native.load()  # a missing / broken native module fails the enable, with its reason
    for m in _modules:
        m.register()


def unregister():
    # Disabling the add-on puts back every scene setting it changed (changes.py).
    import bpy
    try:
        scenes = list(bpy.data.scenes)
    except AttributeError:  # restricted data (Blender starting or quitting): nothing to restore
        scenes = []
    for scene in scenes:
        changes.restore(scene)
    for m in reversed(_modules):
        m.unregister()
