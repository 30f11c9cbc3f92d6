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
from . import changes  # noqa: E402

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
    """Turns on, on every view layer, the passes the filter's settings need or use (needs: the
    native module's needs()) and Cycles' own denoiser off, each change recorded (changes.py) so
    that turning mcrecon off puts it back. Never turns off a pass the user enabled; a pass the
    add-on itself turned on for earlier settings, and these do not read, goes back to the user's
    value. Returns the messages it logged."""
    messages = []

    def say(m):
        messages.append(m)
        log(m)
    on, unavailable = wanted_toggles(needs)
    for vl in scene.view_layers:
        for toggle in {**ROLE_TOGGLES, **LIGHT_TOGGLES}.values():
            owner = changes.layer_path(vl, toggle[0])
            if toggle in on:
                changes.set_value(scene, owner, toggle[1], True, f"'{filter_name}' reads this pass", say)
            elif changes.changed(scene, owner, toggle[1]):
                changes.revert(scene, owner, toggle[1], say)
    names = sorted(("cycles." if o else "") + a for o, a in on)
    say(f"mcrecon: filter '{filter_name}' reads: combined" + (", " + ", ".join(names) if names else " only"))
    if unavailable:
        say(f"mcrecon: Blender does not render {', '.join(unavailable)}; '{filter_name}' runs without them")
    if hasattr(scene, "cycles"):
        changes.set_value(scene, "cycles", "use_denoising", False,
                          "turned off Cycles denoising: mcrecon denoises after the render", say)
    if ("", "use_pass_vector") in on and scene.render.use_motion_blur:
        say("mcrecon: motion blur is on, so Blender drops the Vector (motion) pass")
    return messages


def in_use(scene):
    """The passes on in the first used view layer, by Blender's names, for the panel."""
    vl = next((v for v in scene.view_layers if v.use), scene.view_layers[0])
    names = ["Combined"]
    for role, (owner, attr) in {**ROLE_TOGGLES, **LIGHT_TOGGLES}.items():
        obj = getattr(vl, owner) if owner else vl
        if getattr(obj, attr, False):
            names.append(role.replace("_", " ").title())
    return names
