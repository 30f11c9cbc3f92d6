"""Which Blender pass toggles the pass roles of a filter's settings need, and switching them.
The roles come from the native module's needs() (they depend on the parameters: demodulate=true
needs albedo, accumulate needs position and normal), never from a static list."""

# Role (from the filter tables) -> (owner, attribute) on the view layer; owner "cycles" is
# view_layer.cycles. Denoising Data gives Denoising Albedo / Normal / Depth at once.
ROLE_TOGGLES = {
    "albedo": ("cycles", "denoising_store_passes"),
    "normal": ("", "use_pass_normal"),
    "position": ("", "use_pass_position"),
    "depth": ("", "use_pass_z"),
    "motion": ("", "use_pass_vector"),
}
# Light passes (components=light_passes denoises them one by one): switched on when needed,
# never off, since a compositor may read them.
LIGHT_TOGGLES = {
    "diffuse_direct": ("", "use_pass_diffuse_direct"),
    "diffuse_indirect": ("", "use_pass_diffuse_indirect"),
    "diffuse_colour": ("", "use_pass_diffuse_color"),
    "glossy_direct": ("", "use_pass_glossy_direct"),
    "glossy_indirect": ("", "use_pass_glossy_indirect"),
    "glossy_colour": ("", "use_pass_glossy_color"),
    "transmission_direct": ("", "use_pass_transmission_direct"),
    "transmission_indirect": ("", "use_pass_transmission_indirect"),
    "transmission_colour": ("", "use_pass_transmission_color"),
    "emission": ("", "use_pass_emit"),
    "environment": ("", "use_pass_environment"),
}
# Roles Blender always provides (Combined RGBA) and roles it cannot render.
BUILTIN_ROLES = {"colour", "alpha"}


def _owner(view_layer, owner):
    return getattr(view_layer, owner) if owner else view_layer


def wanted_toggles(needs):
    """(toggles to turn on, roles Blender cannot provide) for needs() = {"required", "optional"}."""
    roles = list(needs["required"]) + list(needs["optional"])
    toggles = {**ROLE_TOGGLES, **LIGHT_TOGGLES}
    on = {toggles[r] for r in roles if r in toggles}
    unavailable = [r for r in roles if r not in toggles and r not in BUILTIN_ROLES]
    return on, unavailable


def apply(scene, filter_name, needs, log=print):
    """Enables exactly the passes the filter's settings need or use (needs: the native module's
    needs()) on every view layer of the scene (light passes: on when needed, never turned off)
    and turns Cycles' own denoiser off. Returns the messages it logged."""
    messages = []
    on, unavailable = wanted_toggles(needs)
    for vl in scene.view_layers:
        for toggle in ROLE_TOGGLES.values():
            owner = _owner(vl, toggle[0])
            if owner is not None and hasattr(owner, toggle[1]):
                setattr(owner, toggle[1], toggle in on)
        for toggle in LIGHT_TOGGLES.values():
            if toggle in on and hasattr(vl, toggle[1]):
                setattr(vl, toggle[1], True)
    names = sorted(("cycles." if o else "") + a for o, a in on)
    messages.append(f"mcrecon: filter '{filter_name}' passes: combined"
                    + (", " + ", ".join(names) if names else " only"))
    if unavailable:
        messages.append(f"mcrecon: Blender does not render {', '.join(unavailable)}; "
                        f"'{filter_name}' runs without them")
    if hasattr(scene, "cycles") and scene.cycles.use_denoising:
        scene.cycles.use_denoising = False
        messages.append("mcrecon: turned off Cycles denoising (scene.cycles.use_denoising); "
                        "mcrecon denoises after the render")
    if ("", "use_pass_vector") in on and scene.render.use_motion_blur:
        messages.append("mcrecon: motion blur is on, so Blender drops the Vector (motion) pass")
    for m in messages:
        log(m)
    return messages
