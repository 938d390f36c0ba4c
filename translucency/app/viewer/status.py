"""The viewer's status text: what is shown and how it was solved, in three lines, and the notes added below it."""

from __future__ import annotations


def status_text(state) -> str:
    """The status of a solved :class:`~translucency.app.viewer.state.ViewerState`: material and size (mm), the
    light (degrees) and the display, the last solve (wall time, vertices, method and tolerance)."""
    result = state.result
    size = float(state.scene.mesh.extent)
    light = (
        "" if state.azimuth is None else f"light azimuth {state.azimuth:.0f} deg, elevation {state.elevation:.0f} deg; "
    )
    # what the last solve used (solve_full and the preview solve by tree, whatever the state's method is)
    method, tol = result.metadata.get("method", state.method), result.metadata.get("tolerance", state.tol)
    used = result.metadata.get("method_used", method)  # what auto chose for this light
    tolerance = "exact sum" if method == "exact" else f"tolerance {tol:.3g}"
    prepared = result.timings.get("solve_prepare", 0.0)
    if state.shows_moving_frame:
        tolerance += "; no bounce while the light moves"
    if used == "relight" and prepared:
        tolerance += f" (operators prepared in {prepared:.0f} s, once)"
    if used == "relight" and result.stats.get("solver", {}).get("relight_fallback"):
        tolerance += f"; by {result.stats['solver']['relight_fallback']}: the operators missed it"
    if str(result.metadata.get("device", "cpu")).startswith("gpu"):
        tolerance += f"; far field on {result.metadata['device']}"
    return (
        f"{state.medium.name}, {state.model} dipole, {size:.3g} mm ({state.mm_per_unit:.4g} mm per unit), "
        f"up {state.up_axis}\n"
        f"{light}display exposure {state.exposure:.3g}"
        + (f"; false colour: {state.false_colour_quantity}, {state.false_colour_scale}" if state.false_colour else "")
        + "\n"
        f"solved in {state.solve_seconds:.2f} s (wall time) on {result.stats['solver_vertices']} of "
        f"{result.stats['vertices']} vertices: {method if used == method else f'{method} ({used})'}, {tolerance}"
    )


def preparing_note(state) -> str:
    """The note while a state's relighting operators are prepared (they take time once per material and model)."""
    return (
        f"preparing the relighting operators for {state.medium.name} on {state.scene.mesh.n_points:,} vertices "
        "(once per material and model; the time grows with the vertices)..."
    )
