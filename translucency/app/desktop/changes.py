"""What each control of the desktop viewer's panel changes: a solve off the window's thread, or at once a
change of what is shown (exposure, false colour, the view-dependent layers), which needs no solve."""

from __future__ import annotations

from ...errors import TranslucencyError


def connect_panel(window) -> None:
    """Connect ``window.panel``'s signals (:class:`~translucency.app.desktop.panel.SidePanel`) and the camera to
    the changes they make on ``window`` (:class:`~translucency.app.desktop.window.MainWindow`)."""
    from ...io.units import UNITS
    from ...scatter.names import check_tol

    panel = window.panel

    def solve(kind, label, change):
        window.request(kind, label, change)

    def prepare(kind, label, change):
        """A change that prepares new relighting operators (tens of seconds): a quick first picture on a coarse
        copy, then every vertex (the state's own solve); other methods solve once."""
        if window.state is not None and window.state.method == "relight":
            solve(kind, f"{label}: a first picture", lambda state: change(state, True))
            solve("solve", f"{label}: preparing the relighting", lambda state: state.solve())
        else:
            solve(kind, label, lambda state: change(state, False))

    def tol(value):
        try:
            check_tol(value)
        except TranslucencyError as exc:
            return window.say(str(exc))
        prepare("solver", f"tolerance {value:g}", lambda state, quick: state.set_tol(value, preview=quick))

    def unit(name):
        window.unit_name = name
        prepare("scale", f"rescaling to {name}", lambda state, quick: state.set_scale(UNITS[name], preview=quick))

    panel.material_chosen.connect(
        lambda choice: prepare(
            "material", f"{_named(choice)}", lambda state, quick: state.set_material(choice, preview=quick)
        )
    )
    panel.model_chosen.connect(
        lambda model: prepare(
            "solver", f"the {model} dipole", lambda state, quick: state.set_model(model, preview=quick)
        )
    )
    panel.tol_chosen.connect(tol)
    panel.bounces_chosen.connect(
        lambda n: solve("solver", f"solving with {n} bounces", lambda state: state.set_bounces(n))
    )
    panel.unit_chosen.connect(unit)
    panel.light_chosen.connect(window.set_light)
    panel.exposure_chosen.connect(lambda v: display(window, lambda state: state.set_exposure(v)))
    panel.false_colour_chosen.connect(
        lambda on, quantity, scale: display(
            window, lambda state: (state.set_false_colour(on, quantity), state.set_false_colour_scale(scale))
        )
    )
    panel.view_dependent_chosen.connect(lambda on: display(window, lambda state: state.set_view_dependent(on)))
    panel.specular_chosen.connect(lambda on: display(window, lambda state: state.set_specular(on)))
    window.view.camera.AddObserver("ModifiedEvent", lambda camera, _event: camera_moved(window, camera))


def _named(choice) -> str:
    """How the status line names a chosen material: its key, its file's name, or its definition's name."""
    from pathlib import Path

    if isinstance(choice, dict):
        return str(choice.get("name", "the material"))
    return Path(str(choice)).stem if str(choice).endswith((".toml", ".json")) else str(choice)


def display(window, change) -> None:
    """A change of what is shown (no solve): made on the window's thread and drawn at once."""
    if window.state is None or window.state.result is None:
        return
    window.guarded(lambda: change(window.state))
    window.redraw(keep_message=True)


def camera_moved(window, camera) -> None:
    """The camera moved: the view-dependent layers follow it (no solve)."""
    state = window.state
    if state is not None and state.result is not None and state.set_eye(camera.GetPosition()):
        window.layers.recolour(state)
