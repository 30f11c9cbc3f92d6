"""scene.mcrecon: settings plus one PropertyGroup per filter, generated from the parameter
tables of the native module (names, types, defaults, ranges, choices and help; labels, tooltips
and menus as panel_layout.py words them)."""
import bpy

from . import native, pass_output, panel_layout, passes

INT32 = 2**31 - 1
_classes = []          # registered classes, in order
_prop_names = {}       # filter -> {parameter name: property name}
RESERVED = {"name", "rna_type", "bl_rna"}


def group_attr(filter_name):
    return "params_" + filter_name


def prop_name(param):
    return "p_" + param if param in RESERVED else param


def _property(spec):
    t = spec["type"]
    common = dict(name=panel_layout.label(spec["name"]), description=panel_layout.tooltip(spec),
                  update=_on_param_change)
    choices = panel_layout.int_choices(spec)
    if choices:  # a small integer whose values have names: a menu
        return bpy.props.EnumProperty(items=choices, default=str(int(spec["default"])), **common)
    if t == "int":
        lo, hi = max(int(spec["min"]), -INT32), min(int(spec["max"]), INT32)
        return bpy.props.IntProperty(default=int(spec["default"]), min=lo, max=hi, **common)
    if t == "float":
        return bpy.props.FloatProperty(default=float(spec["default"]), min=float(spec["min"]),
                                       max=float(spec["max"]), precision=4, **common)
    if t == "bool":
        return bpy.props.BoolProperty(default=bool(spec["default"]), **common)
    if t == "enum":
        items = [(c, c.replace("_", " ").title(), spec["help"]) for c in spec["choices"]]
        return bpy.props.EnumProperty(items=items, default=spec["default"], **common)
    raise ValueError(f"parameter {spec['name']}: unknown type {t}")


def value_of(group, filter_name, spec):
    """A parameter's value as the table types it (a menu of integers gives its int)."""
    v = getattr(group, _prop_names[filter_name][spec["name"]])
    return int(v) if spec["type"] == "int" and isinstance(v, str) else v


def _filter_group(info):
    ann, names = {}, {}
    for spec in info["parameters"]:
        p = prop_name(spec["name"])
        ann[p] = _property(spec)
        names[spec["name"]] = p
    _prop_names[info["name"]] = names
    cls = type("MCRECON_PG_" + info["name"], (bpy.types.PropertyGroup,), {"__annotations__": ann})
    cls.__doc__ = f"mcrecon '{info['name']}' parameters"
    return cls


def filter_params(settings, filter_name):
    """The parameters of the filter that differ from their defaults, as a dict for the
    native module (unchanged ones are left to the core, so float32 storage of a default never
    matters), plus the key=value pairs of settings.extra_params."""
    mc = native.get()
    info = mc.filter_info(filter_name)
    group = getattr(settings, group_attr(filter_name))
    out = {}
    for spec in info["parameters"]:
        v = value_of(group, filter_name, spec)
        d = spec["default"]
        if spec["type"] == "float":
            if abs(v - d) <= 1e-6 * max(1.0, abs(d)):
                continue
            v = min(max(float(v), spec["min"]), spec["max"])
        elif v == d:
            continue
        out[spec["name"]] = v
    if settings.light_passes:
        out["components"] = "light_passes"
    for token in settings.extra_params.split():
        key, eq, value = token.partition("=")
        if not eq or not key:
            err = mc.Error(f"extra parameters: expected KEY=VALUE, got '{token}'")
            err.kind = "invalid_argument"
            raise err
        out[key] = value
    return out


def needs(settings):
    """What the scene's filter settings (parameters, extra parameters, accumulate) need and use:
    the native module's needs(). Raises mcrecon.Error for bad settings."""
    return native.get().needs(settings.filter, filter_params(settings, settings.filter),
                              accumulate=settings.accumulate)


def apply_passes(scene, log=print):
    """Enables the passes the scene's settings need or use (passes.apply); returns its messages.
    Raises mcrecon.Error for bad settings (nothing is changed then)."""
    settings = scene.mcrecon
    return passes.apply(scene, settings.filter, needs(settings), log)


def _apply_or_report(scene):
    mc = native.get()
    try:
        apply_passes(scene)
    except mc.Error as e:
        line = f"mcrecon: ERROR: passes not changed: {e} [{e.kind}]"
        print(line, flush=True)
        scene.mcrecon.last_message = line


def _on_filter_change(self, context):
    scene = self.id_data
    if self.enabled:
        _apply_or_report(scene)
    pass_output.ensure(scene)


def _on_param_change(self, context):
    """A parameter of a filter group changed: the chosen filter's needs may have too."""
    scene = self.id_data
    settings = scene.mcrecon
    chosen = getattr(settings, group_attr(settings.filter))
    if settings.enabled and chosen.as_pointer() == self.as_pointer():
        _apply_or_report(scene)
        pass_output.ensure(scene)  # its File Output node links the passes now on


def _base_annotations():
    return {
        "enabled": bpy.props.BoolProperty(
            name="Denoise with mcrecon", default=False, update=_on_filter_change,
            description="Run the mcrecon filter after every render (reads the passes from the multilayer EXR)"),
        "output_path": bpy.props.StringProperty(
            name="Output", subtype="FILE_PATH", default="",
            description="Denoised output (#### = frame; without #, an animation's frames get the frame number "
                        "before the extension, as Blender numbers its own: out0001.exr); never the render itself; "
                        "empty: <render>_denoised.exr next to the render"),
        "accumulate": bpy.props.BoolProperty(
            name="Accumulate", default=False, update=_on_filter_change,
            description="Temporally accumulate the noisy colour across the frames of an animation before the "
                        "filter (as mcrecon denoise --accumulate; needs the Position and Normal passes, uses "
                        "Vector); history restarts on a frame jump"),
        "light_passes": bpy.props.BoolProperty(
            name="Denoise Light Passes", default=False, update=_on_filter_change,
            description="Denoise Blender's diffuse, glossy and transmission light one by one, each by its own "
                        "colour pass, and add them up (components=light_passes; turns the light passes on: "
                        "Diffuse, Glossy, Transmission Direct/Indirect/Color, Emission, Environment)"),
        "keep_components": bpy.props.BoolProperty(
            name="Keep Components", default=False,
            description="With Denoise light passes: write each denoised component as its own layer of the output "
                        "(<layer>.Denoised.Diffuse, Glossy, Transmission, Emission, Environment), summing to "
                        "the beauty (mcrecon denoise --keep-components)"),
        "before_compositing": bpy.props.BoolProperty(
            name="Denoise Before Compositing", default=True,
            description="With compositing on: denoise the raw render, then run your compositor nodes on the "
                        "denoised image (grade and glare apply to it, as Blender's Denoise node placed right after "
                        "Render Layers would); off: denoise the compositor's output"),
        "extra_params": bpy.props.StringProperty(
            name="Extra Parameters", default="", update=_on_filter_change,
            description="Advanced: KEY=VALUE pairs passed to the filter as they are (like mcrecon denoise --set)"),
        "last_message": bpy.props.StringProperty(name="Last message", default=""),
    }


def register():
    infos = native.get().filters()
    _classes.clear()
    ann = _base_annotations()
    for info in infos:
        cls = _filter_group(info)
        bpy.utils.register_class(cls)
        _classes.append(cls)
        ann[group_attr(info["name"])] = bpy.props.PointerProperty(type=cls)
    ann["filter"] = bpy.props.EnumProperty(
        # A render is flat: per-sample filters (sweep) are for Denoise EXR Files on deep EXRs.
        name="Filter", items=[(i["name"], panel_layout.filter_label(i["name"]), i["summary"]) for i in infos
                              if i.get("input") != "deep"],
        # auto: a new user gets the filter that suits the render (and the passes it may read).
        default="auto", update=_on_filter_change,
        description="mcrecon filter (Render properties show its parameters)")
    settings = type("MCRECON_PG_settings", (bpy.types.PropertyGroup,), {"__annotations__": ann})
    settings.__doc__ = "scene.mcrecon: mcrecon denoiser settings"
    bpy.utils.register_class(settings)
    _classes.append(settings)
    bpy.types.Scene.mcrecon = bpy.props.PointerProperty(type=settings)


def unregister():
    del bpy.types.Scene.mcrecon
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
    _classes.clear()
