"""Render properties > mcrecon Denoiser: the switch, the filter and its main settings, then
collapsed sub-panels (Features, Fireflies, Foveation, Advanced, Scene Changes). A setting is
drawn only when it has an effect under the current settings (the core's own rule:
mcrecon.inactive_parameters); the passes in use and the last message are shown in full."""
import bpy

from . import changes, native, panel_layout, passes, properties

_inactive_cache = {}


def _inactive(settings):
    """Parameters of the chosen filter with no effect now (cached per settings)."""
    try:
        params = properties.filter_params(settings, settings.filter)
    except Exception:  # bad extra parameters: the message says so; draw everything
        return set()
    key = (settings.filter, tuple(sorted((k, str(v)) for k, v in params.items())))
    if key not in _inactive_cache:
        if len(_inactive_cache) > 256:
            _inactive_cache.clear()
        try:
            _inactive_cache[key] = set(native.get().inactive_parameters(settings.filter, params))
        except Exception:
            _inactive_cache[key] = set()
    return _inactive_cache[key]


def _params_of(context, group):
    mc = context.scene.mcrecon
    info = native.get().filter_info(mc.filter)
    return [s["name"] for s in info["parameters"] if panel_layout.group_of(s["name"]) == group]


def _draw_params(layout, context, group, skip=()):
    mc = context.scene.mcrecon
    values = getattr(mc, properties.group_attr(mc.filter))
    hidden = _inactive(mc)
    col = layout.column()
    for name in _params_of(context, group):
        if name not in hidden and name not in skip:
            col.prop(values, properties.prop_name(name))


def _label_lines(layout, text, icon="NONE"):
    col = layout.column(align=True)
    for i, line in enumerate(panel_layout.wrap(text)):
        col.label(text=line, icon=icon if i == 0 else "BLANK1" if icon != "NONE" else "NONE")


class MCRECON_PT_render(bpy.types.Panel):
    bl_label = "mcrecon Denoiser"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw_header(self, context):
        self.layout.prop(context.scene.mcrecon, "enabled", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        mc = context.scene.mcrecon
        layout.active = mc.enabled
        layout.prop(mc, "filter")
        _label_lines(layout, native.get().filter_info(mc.filter)["summary"])
        _draw_params(layout, context, "main")
        layout.prop(mc, "accumulate")
        layout.prop(mc, "light_passes")
        if mc.light_passes:
            layout.prop(mc, "keep_components")
        layout.prop(mc, "before_compositing")
        layout.prop(mc, "output_path")
        _label_lines(layout, "Passes in use: " + ", ".join(passes.in_use(context.scene)), icon="RENDERLAYERS")
        row = layout.row()
        row.operator("mcrecon.apply_passes")
        row.operator("mcrecon.denoise_files")
        if mc.last_message:
            _label_lines(layout, mc.last_message, icon="ERROR" if "ERROR" in mc.last_message else "INFO")


class _Sub:
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_parent_id = "MCRECON_PT_render"
    bl_options = {"DEFAULT_CLOSED"}
    group = ""

    @classmethod
    def poll(cls, context):
        return bool(_params_of(context, cls.group))

    def draw(self, context):
        self.layout.use_property_split = True
        self.layout.use_property_decorate = False
        self.layout.active = context.scene.mcrecon.enabled
        _draw_params(self.layout, context, self.group)


class MCRECON_PT_features(_Sub, bpy.types.Panel):
    bl_label = "Features"
    group = "features"


class MCRECON_PT_fireflies(_Sub, bpy.types.Panel):
    bl_label = "Fireflies"
    group = "fireflies"


class MCRECON_PT_foveation(_Sub, bpy.types.Panel):
    bl_label = "Foveation"
    group = "foveation"

    def draw_header(self, context):
        mc = context.scene.mcrecon
        values = getattr(mc, properties.group_attr(mc.filter))
        self.layout.prop(values, properties.prop_name("foveated"), text="")

    def draw(self, context):
        self.layout.use_property_split = True
        self.layout.use_property_decorate = False
        self.layout.active = context.scene.mcrecon.enabled
        _draw_params(self.layout, context, self.group, skip=("foveated",))


class MCRECON_PT_advanced(_Sub, bpy.types.Panel):
    bl_label = "Advanced"
    group = "advanced"

    @classmethod
    def poll(cls, context):
        return True  # Extra Parameters always

    def draw(self, context):
        _Sub.draw(self, context)
        self.layout.prop(context.scene.mcrecon, "extra_params")


class MCRECON_PT_changes(bpy.types.Panel):
    bl_label = "Scene Changes"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_parent_id = "MCRECON_PT_render"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        return bool(changes.listing(context.scene))

    def draw(self, context):
        col = self.layout.column(align=True)
        for line in changes.listing(context.scene):
            for i, part in enumerate(panel_layout.wrap(line)):
                col.label(text=part, icon="DOT" if i == 0 else "BLANK1")
        self.layout.operator("mcrecon.restore_scene")


def draw_render_menu(self, context):
    """Render menu entries (F3 finds them by "mcrecon")."""
    layout = self.layout
    layout.separator()
    op = layout.operator("mcrecon.render", text="Render Denoised Image (mcrecon)", icon="RENDER_STILL")
    op.animation = False
    op = layout.operator("mcrecon.render", text="Render Denoised Animation (mcrecon)", icon="RENDER_ANIMATION")
    op.animation = True
    layout.operator("mcrecon.denoise_files", text="Denoise EXR Files (mcrecon)", icon="FILE_IMAGE")
    layout.operator("mcrecon.render_halves", text="Render Halves and Denoise (mcrecon)", icon="RENDER_STILL")
    layout.operator("mcrecon.export_deep", text="Export Per-Sample EXR (mcrecon)", icon="OUTLINER_DATA_POINTCLOUD")


def draw_compositor_add_menu(self, context):
    """The compositor's Add menu: Blender 3.4 cannot add a Python node, so this says where the
    denoised image enters and holds the switches."""
    if getattr(context.space_data, "tree_type", "") != "CompositorNodeTree" or not hasattr(context.scene, "mcrecon"):
        return
    layout = self.layout
    layout.separator()
    layout.label(text="mcrecon Denoiser (replaces Render Layers' Image)", icon="SHADERFX")
    layout.prop(context.scene.mcrecon, "enabled", text="mcrecon Denoise Renders")
    layout.prop(context.scene.mcrecon, "before_compositing")


_menus = ((lambda: bpy.types.TOPBAR_MT_render, draw_render_menu),
          (lambda: bpy.types.NODE_MT_add, draw_compositor_add_menu))

_classes = (MCRECON_PT_render, MCRECON_PT_features, MCRECON_PT_fireflies, MCRECON_PT_foveation,
            MCRECON_PT_advanced, MCRECON_PT_changes)


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    for menu, fn in _menus:
        menu().append(fn)


def unregister():
    for menu, fn in _menus:
        menu().remove(fn)
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
