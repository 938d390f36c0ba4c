"""The viewer's state without a window: what re-solves and what only re-displays, with no PyVista or VTK loaded."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from translucency.app.viewer.state import ViewerState, light_direction
from translucency.errors import InvalidParameterError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.io.baked import read_baked_ply
from translucency.scatter.lights import EnvironmentLight


@pytest.fixture(scope="module")
def sphere():
    points, triangles = icosphere(3, 20.0)  # 642 vertices, 40 mm across
    return TriangleMesh(points, triangles)


@pytest.fixture
def state(sphere):
    return ViewerState(sphere, "marble", method="exact")


def count_solves(state, monkeypatch):
    """Count the calls of ``state.scene.shade`` (the one solve) from now on; returns the list of calls."""
    calls = []
    shade = state.scene.shade

    def counted(*args, **kwargs):
        calls.append(kwargs.get("resolution"))
        return shade(*args, **kwargs)

    monkeypatch.setattr(state.scene, "shade", counted)
    return calls


def test_the_state_imports_neither_pyvista_nor_vtk():
    code = textwrap.dedent("""
        import sys
        import numpy as np
        from translucency.app.viewer.state import ViewerState
        from translucency.geometry.mesh import TriangleMesh
        from translucency.geometry.synthetic import icosphere

        points, triangles = icosphere(2, 20.0)
        state = ViewerState(TriangleMesh(points, triangles), "marble", method="exact", view_dependent=True,
                            specular=True)
        state.set_light(40, 10)
        state.set_material("ketchup")
        colors = state.colors(eye=(0.0, 0.0, 100.0))
        assert colors.shape == (len(points), 3) and colors.max() > 0
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("pyvista", "vtk", "vtkmodules"))
        print("loaded:", loaded)
    """)
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "loaded: []" in run.stdout, run.stdout


def test_set_light_solves_again_and_the_bright_side_follows_the_light(state, sphere, monkeypatch):
    solves = count_solves(state, monkeypatch)
    before = state.colors().astype(float)
    assert state.set_light(-140.0, -20.0) is True
    assert len(solves) == 1 and state.n_solves == 2
    assert (state.azimuth, state.elevation) == (-140.0, -20.0)
    np.testing.assert_allclose(
        state.lights[state.key_light].direction, light_direction(-140.0, -20.0, state.up), atol=1e-12
    )
    after = state.colors().astype(float)
    assert np.abs(after - before).mean() > 10
    facing = sphere.vertex_normals() @ light_direction(-140.0, -20.0, state.up)
    assert after[facing > 0.5].mean() > after[facing < -0.5].mean() + 50
    assert "azimuth -140 deg, elevation -20 deg" in state.status


def test_an_unchanged_setting_neither_solves_nor_changes_the_picture(state, monkeypatch):
    solves = count_solves(state, monkeypatch)
    assert state.set_light(state.azimuth, state.elevation) is False
    assert state.set_material("marble") is False
    assert state.set_model(state.model) is False
    assert state.set_scale(state.mm_per_unit) is False
    assert state.set_exposure(state.exposure) is False
    assert state.set_view_dependent(False) is False and state.set_specular(False) is False
    assert solves == [] and state.n_solves == 1


def test_set_exposure_changes_the_colours_without_a_solve(state, monkeypatch):
    solves = count_solves(state, monkeypatch)
    before, exposure, result = state.colors().astype(float), state.exposure, state.result
    assert state.set_exposure(2 * exposure) is True
    assert solves == [] and state.n_solves == 1 and state.result is result
    assert state.colors().astype(float).mean() > before.mean() + 5
    assert f"exposure {2 * exposure:.3g}" in state.status


def test_the_exposure_of_the_first_solve_is_kept_across_solves(state):
    exposure = state.exposure
    assert exposure == pytest.approx(state.result.exposure)
    state.set_material("skim_milk")
    assert state.exposure == exposure and state.result.exposure == exposure


def test_material_and_model_solve_again(state, monkeypatch):
    solves = count_solves(state, monkeypatch)
    marble = state.colors().astype(float)
    assert state.set_material("ketchup") is True
    ketchup = state.colors().astype(float)
    red_over_blue = lambda c: c[:, 0].mean() / max(c[:, 2].mean(), 1.0)  # noqa: E731
    assert red_over_blue(ketchup) > 1.5 * red_over_blue(marble)
    assert state.set_model("standard") is True
    assert len(solves) == 2 and state.status.startswith("ketchup, standard dipole")
    assert np.abs(state.colors().astype(float) - ketchup).mean() > 1


@pytest.mark.parametrize("factor", [1e-3, 0.25, 4.0, 1e3])
def test_set_scale_makes_a_new_scene_and_keeps_results_finite(sphere, factor):
    state = ViewerState(sphere, "marble", method="exact")
    scene = state.scene
    assert state.set_scale(factor) is True
    assert state.scene is not scene and state.n_solves == 2
    assert np.isclose(state.scene.mesh.extent, factor * sphere.extent)
    B, radiance = state.result.B, state.result.radiance
    assert np.all(np.isfinite(B)) and np.all(B >= 0) and np.all(np.isfinite(radiance))
    assert B.max() > 0
    colors = state.colors()
    assert colors.dtype == np.uint8 and colors.shape == (sphere.n_points, 3)


def test_a_larger_object_is_darker_on_its_far_side(sphere):
    state = ViewerState(sphere, "marble", method="exact")
    facing = sphere.vertex_normals() @ state.lights[0].direction
    small = state.result.B[facing < -0.5].mean() / state.result.B[facing > 0.5].mean()
    state.set_scale(3.0)
    large = state.result.B[facing < -0.5].mean() / state.result.B[facing > 0.5].mean()
    assert large < small
    assert "120 mm (3 mm per unit)" in state.status


def test_view_dependent_layer_needs_the_camera_and_never_solves(state, sphere, monkeypatch):
    solves = count_solves(state, monkeypatch)
    normal_view = state.colors().astype(float)
    assert state.set_view_dependent(True) is True
    np.testing.assert_array_equal(state.colors(), normal_view)  # no camera position yet: the layer waits
    eye = np.array([0.0, 0.0, 100.0])
    assert state.set_eye(eye) is True and state.set_eye(eye) is False  # moved once, then the same place
    shown = state.colors().astype(float)
    w_o = eye - sphere.points
    cos_o = np.einsum("ij,ij->i", sphere.vertex_normals(), w_o / np.linalg.norm(w_o, axis=1, keepdims=True))
    grazing = (cos_o > 0) & (cos_o < 0.2) & (normal_view.max(axis=1) > 30)
    assert grazing.sum() > 5 and np.all(shown[grazing].max(axis=1) < normal_view[grazing].max(axis=1))
    other = state.colors(eye=(100.0, 0.0, 0.0)).astype(float)
    assert np.abs(other - shown).mean() > 1 and state.eye == (100.0, 0.0, 0.0)
    assert solves == []


def test_set_eye_says_nothing_changed_while_the_layers_are_off(state):
    assert state.set_eye((0.0, 0.0, 100.0)) is False  # moved, but nothing shown depends on it
    assert state.eye == (0.0, 0.0, 100.0)


def test_specular_highlight_adds_light_without_a_solve(state, monkeypatch):
    solves = count_solves(state, monkeypatch)
    before = state.colors(eye=(0.0, 0.0, 100.0)).astype(int)
    assert state.set_specular(True) is True
    after = state.colors().astype(int)
    assert solves == []
    assert np.all(after >= before) and (after > before + 2).any(axis=1).sum() > 3
    radiance = state.radiance_shown()
    assert np.all(np.isfinite(radiance)) and np.all(radiance >= state.result.radiance - 1e-12)


def test_solve_full_solves_on_every_vertex(sphere):
    state = ViewerState(sphere.replace(points=sphere.points * 8), "marble", resolution=40.0)
    assert state.result.stats["solver_vertices"] < sphere.n_points
    state.solve_full()
    assert state.result.stats["solver_vertices"] == sphere.n_points
    assert f"{sphere.n_points} of {sphere.n_points} vertices" in state.status
    state.set_exposure(1.0)  # a later change goes back to the state's own resolution only when it solves
    assert state.result.stats["solver_vertices"] == sphere.n_points
    state.set_light(0.0, 45.0)
    assert state.result.stats["solver_vertices"] < sphere.n_points


def test_bad_values_are_refused_and_leave_the_state_as_it_was(state):
    before = (state.azimuth, state.elevation, state.exposure, state.mm_per_unit, state.model, state.n_solves)
    with pytest.raises(InvalidParameterError, match="elevation"):
        state.set_light(0.0, 120.0)
    with pytest.raises(InvalidParameterError, match="exposure"):
        state.set_exposure(-1)
    with pytest.raises(InvalidParameterError, match="scale"):
        state.set_scale(float("nan"))
    with pytest.raises(InvalidParameterError, match="unknown model"):
        state.set_model("no such model")
    assert (state.azimuth, state.elevation, state.exposure, state.mm_per_unit, state.model, state.n_solves) == before


def test_without_a_directional_light_there_is_nothing_to_steer(sphere):
    state = ViewerState(sphere, "marble", EnvironmentLight(1.0, n_directions=16), method="exact")
    assert state.key_light is None and state.azimuth is None and "azimuth" not in state.status
    with pytest.raises(InvalidParameterError, match="no directional light"):
        state.set_light(10, 20)


def test_a_state_made_without_solving_solves_when_asked(sphere):
    state = ViewerState(sphere, "marble", method="exact", solve=False)
    assert state.result is None and state.n_solves == 0 and state.status == ""
    state.solve()
    assert state.n_solves == 1 and state.result.B.shape == (sphere.n_points, 3)
    assert "marble, directional dipole" in state.status and "exact sum" in state.status


def test_a_note_lasts_until_the_next_change(state):
    state.add_note("saved a.png and a.ply")
    state.add_note("saved b.png and b.ply")
    assert state.status.endswith("\nsaved b.png and b.ply") and "a.png" not in state.status
    state.set_exposure(2 * state.exposure)
    assert "saved" not in state.status


def test_the_bake_holds_the_radiance_toward_the_normal_at_the_current_exposure(state, tmp_path):
    state.set_view_dependent(True)
    state.set_eye((0.0, 0.0, 100.0))
    state.set_exposure(3 * state.exposure)
    path = state.write_bake(tmp_path / f"{state.file_stem}.ply")
    assert path.name == "scan_marble_directional.ply"
    baked = read_baked_ply(path)
    np.testing.assert_allclose(baked.radiance, state.result.radiance, rtol=1e-6, atol=1e-9)
    assert baked.metadata["exposure"] == pytest.approx(state.exposure)
    state.set_view_dependent(False)
    np.testing.assert_array_equal(np.asarray(baked.colors_rgb8), state.colors())  # the view-independent colours


def test_false_colour_shows_the_luminance_without_a_solve(state, monkeypatch):
    from translucency.app.display import luminance

    calls = count_solves(state, monkeypatch)
    assert state.set_false_colour(True) and state.false_colour and not state.set_false_colour(True)
    # the luminance of what is shown (Rec. 709 of the linear radiance), in W/(m^2 sr) per W/m^2
    np.testing.assert_allclose(state.false_colour_values(), luminance(state.radiance_shown()))
    assert "false colour: luminance, log" in state.status
    low, high = state.false_colour_range()
    assert np.isclose(high, 1.0 / state.exposure) and np.isclose(low, high / 1000)
    assert state.set_false_colour_scale("linear") and state.false_colour_range()[0] == 0.0
    state.set_false_colour(True, "red")
    np.testing.assert_array_equal(state.false_colour_values(), state.result.radiance[:, 0])
    assert "linear scale" in state.false_colour_title and "W/(m² sr)" in state.false_colour_title
    with pytest.raises(InvalidParameterError, match="log, linear"):
        state.set_false_colour_scale("sqrt")
    with pytest.raises(InvalidParameterError, match="luminance"):
        state.set_false_colour(True, "hue")
    assert calls == []


def test_tolerance_bounces_and_lights_solve_again(state, monkeypatch):
    from translucency.scatter.lights import DirectionalLight, PointLight

    calls = count_solves(state, monkeypatch)
    assert state.set_tol(0.05) is True and state.tol == 0.05
    assert state.set_bounces(0) is True and state.bounces == 0
    assert state.set_tol(0.05) is False and state.set_bounces(0) is False and len(calls) == 2
    lamp = PointLight((0.0, 80.0, 0.0), 6.4e-3)  # 1 W/m² at the centre, 80 mm away
    assert state.set_lights(lamp) is True and len(calls) == 3
    assert state.key_light is None and state.azimuth is None  # nothing left for set_light to steer
    top = state.result.radiance[:, 1][state.base_mesh.points[:, 1] > 15].mean()
    bottom = state.result.radiance[:, 1][state.base_mesh.points[:, 1] < -15].mean()
    assert top > 10 * bottom  # lit from above
    assert state.set_lights([DirectionalLight((1.0, 0.0, 0.0))]) is True
    assert state.key_light == 0 and state.azimuth == pytest.approx(90.0) and state.elevation == pytest.approx(0.0)
    with pytest.raises(InvalidParameterError, match="relative error in"):
        state.set_tol(2.0)


class _Stop(BaseException):
    pass


def test_a_solve_stopped_by_its_progress_leaves_the_settings_and_picture_as_they_were(state):
    colours = state.colors().copy()
    medium, model = state.medium.name, state.model

    def stop(stage, fraction):
        raise _Stop

    state.on_progress = stop
    for change in (lambda: state.set_material("ketchup"), lambda: state.set_model("standard")):
        with pytest.raises(_Stop):
            change()
    assert (state.medium.name, state.model) == (medium, model)
    np.testing.assert_array_equal(state.colors(), colours)


def test_the_preview_is_a_coarse_tree_solve_and_the_method_stays(sphere):
    state = ViewerState(sphere, "marble", solve=False, method="relight", tol=0.1)
    state.solve_preview()
    assert state.result.metadata["method"] == "tree"  # no operators prepared for the first picture
    assert state.method == "relight" and state.result.stats["solver_vertices"] <= sphere.n_points


def test_the_status_names_the_method_that_solved_what_is_shown(sphere):
    state = ViewerState(sphere, "marble", method="relight", tol=0.1)
    assert "relight, tolerance 0.1" in state.status
    state.solve_full()  # by tree at the default tolerance, whatever the state's own method
    assert state.method == "relight" and "tree, tolerance 0.01" in state.status
    state.solve_preview()
    assert "tree, tolerance 0.1" in state.status


def test_the_status_says_when_relighting_gave_way_to_tree(sphere):
    """An index of refraction of 1, where the operators' fits to the refracted direction fail: every light is
    solved by tree, and the status says so (the warning says why)."""
    from translucency.errors import TranslucencyWarning
    from translucency.scatter.lights import DirectionalLight
    from translucency.scatter.materials import material
    from translucency.scatter.medium import Medium

    marble = material("marble").medium()
    matched = Medium(marble.sigma_a, marble.sigma_s, marble.g, 1.0, "index-matched marble")
    with pytest.warns(TranslucencyWarning, match="solved by tree instead"):
        state = ViewerState(sphere, matched, bounces=0)
    assert "relight, tolerance 0.01" in state.status and "by tree: the operators missed it" in state.status
    state.set_light(-40.0, 20.0)
    assert "by tree: the operators missed it" in state.status
    # two lights summed apart (per direction): several solves, and the status still says so
    lights = [DirectionalLight((0.0, 1.0, 0.2), 1.0), DirectionalLight((1.0, 0.0, 0.5), 1.0)]
    with pytest.warns(TranslucencyWarning, match="solved by tree instead"):
        many = ViewerState(sphere, matched, lights=lights, bounces=0, per_direction=True)
    assert many.result.stats["solver"]["solves"] == 2 and "by tree: the operators missed it" in many.status


def test_a_frame_while_the_light_moves_leaves_the_bounce_out_and_the_next_solves_it_whole(sphere):
    from translucency.scatter.lights import DirectionalLight

    state = ViewerState(sphere, "marble", method="exact", bounces=1)
    light = DirectionalLight((0.0, 1.0, 1.0))
    assert state.set_lights(light, moving=True) is True
    assert state.result.metadata["bounces"] == 0 and state.bounces == 1
    assert "no bounce while the light moves" in state.status
    assert state.set_lights(light, moving=True) is False  # the same frame again: nothing to do
    assert state.set_lights(light) is True  # let go: the same light, whole
    assert state.result.metadata["bounces"] == 1 and "no bounce" not in state.status
    assert state.set_lights(light) is False


def test_the_viewer_relights_with_its_far_field_on_a_gpu_and_says_so():
    """In numba's CUDA simulator (a process of its own, no GPU needed), ``device="gpu"``: the first picture by tree,
    then relighting with every pair of its far field, both on the GPU, and the status line names the device."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    code = (
        "from translucency.app.viewer.state import ViewerState\n"
        "from translucency.geometry.mesh import TriangleMesh\n"
        "from translucency.geometry.synthetic import icosphere\n"
        "state = ViewerState(TriangleMesh(*icosphere(2, 20.0)), 'marble', device='gpu', bounces=0)\n"
        "state.solve_preview()\n"
        "print(state.result.metadata['device'], state.result.metadata['method'])\n"
        "state.set_light(-40.0, 20.0)\n"
        "print(state.result.metadata['device'])\n"
        "print(state.status.replace(chr(10), ' '))\n"
    )
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1", "PYTHONPATH": str(root)}
    child = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True, timeout=300)
    assert child.returncode == 0, child.stderr[-3000:]
    preview, device, status = child.stdout.strip().splitlines()[-3:]
    assert preview == "gpu (CUDA simulator) tree" and device == "gpu (CUDA simulator)"
    assert "relight, tolerance 0.01" in status and "far field on gpu (CUDA simulator)" in status
