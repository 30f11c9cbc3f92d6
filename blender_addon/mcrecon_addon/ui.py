"""Render properties > mcrecon: the switch, the filter and its generated parameters."""
import bpy

from . import changes, native, passes, properties


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
        mc = context.scene.mcrecon
        layout.active = mc.enabled
        layout.prop(mc, "filter")
        layout.prop(mc, "accumulate")
        layout.prop(mc, "light_passes")
        row = layout.row()
        row.active = mc.light_passes
        row.prop(mc, "keep_components")
        info = native.get().filter_info(mc.filter)
        layout.label(text=info["summary"])
        group = getattr(mc, properties.group_attr(mc.filter))
        col = layout.column()
        for spec in info["parameters"]:
            col.prop(group, properties.prop_name(spec["name"]))
        layout.prop(mc, "extra_params")
        layout.prop(mc, "output_path")
        row = layout.row()
        row.operator("mcrecon.apply_passes")
        row.operator("mcrecon.denoise_files")
        col = layout.column(align=True)
        col.label(text="Passes in use: " + ", ".join(passes.in_use(context.scene)))
        made = changes.listing(context.scene)
        if made:
            col.label(text=f"Scene settings changed by mcrecon ({len(made)}):")
            for line in made:
                col.label(text=line)
            col.operator("mcrecon.restore_scene")
        if mc.last_message:
            layout.label(text=mc.last_message, icon="ERROR" if "ERROR" in mc.last_message else "INFO")


def register():
    bpy.utils.register_class(MCRECON_PT_render)


def unregister():
    bpy.utils.unregister_class(MCRECON_PT_render)
