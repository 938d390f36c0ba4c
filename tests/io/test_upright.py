"""The up axis of a scan: parsing, the flat-stable-base rule, and the display frame."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, command_line_spelling
from translucency.io.upright import (
    AXES,
    FALLBACK_UP,
    base_scores,
    display_frame,
    infer_up,
    parse_up,
    resolve_up,
    to_scan_frame,
    up_vector,
)

from .conftest import icosphere, load_scan


@pytest.mark.parametrize("text, axis", [("y", "+y"), ("+Y", "+y"), ("-z", "-z"), ("x", "+x"), (" auto ", "auto")])
def test_parse_up(text, axis):
    assert parse_up(text) == axis


@pytest.mark.parametrize("text", ["w", "--z", "+-x", "xy", "", None, 1])
def test_parse_up_refuses_with_the_choices(text):
    with pytest.raises(InvalidParameterError, match=r"x, y, z, -x, -y, -z, auto.*up='z'"):
        parse_up(text)
    with command_line_spelling(), pytest.raises(InvalidParameterError, match="--up z"):
        parse_up(text)


@pytest.mark.parametrize("up", AXES)
def test_display_frame_is_a_rotation_with_up_as_its_second_row(up):
    frame = display_frame(up)
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(frame) == pytest.approx(1.0)
    np.testing.assert_array_equal(frame[1], up_vector(up))
    np.testing.assert_allclose(to_scan_frame((0, 1, 0), up), up_vector(up))


def test_y_up_frame_is_the_identity_and_z_up_looks_from_minus_y():
    np.testing.assert_array_equal(display_frame("+y"), np.eye(3))
    np.testing.assert_array_equal(to_scan_frame((0, 0, 1), "+z"), (0, -1, 0))  # front of a Z-up scan


def _box_on_a_plinth(up_index):
    """A closed stepped solid (wide plinth, narrow column) standing on its lowest coordinate along ``up_index``."""
    import pyvista

    plinth = pyvista.Box((-30, 30, -30, 30, 0, 10)).triangulate()
    column = pyvista.Box((-8, 8, -8, 8, 10, 90)).triangulate()
    poly = plinth.merge(column)
    points = np.roll(np.array(poly.points), up_index - 2, axis=1)  # z onto the axis (a rotation: cyclic)
    return points, np.asarray(poly.faces).reshape(-1, 4)[:, 1:]


@pytest.mark.parametrize("up_index, expected", [(0, "+x"), (1, "+y"), (2, "+z")])
def test_a_plinth_is_the_base_whatever_the_axis(up_index, expected):
    points, triangles = _box_on_a_plinth(up_index)
    assert infer_up(points, triangles)[0] == expected
    flipped = points.copy()
    flipped[:, up_index] *= -1  # upside down: the plinth is on top
    assert infer_up(flipped, triangles[:, ::-1])[0] == "-" + expected[1]


def test_a_ball_has_no_base_and_falls_back():
    points, triangles = icosphere(3, 20.0)
    up, reason = infer_up(points, triangles)
    assert up == FALLBACK_UP and "no flat" in reason
    assert all(score is None or score < 0.005 for score in base_scores(points, triangles).values())


def test_flat_meshes_and_given_axes():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    assert infer_up(points, [[0, 1, 2]])[0] == FALLBACK_UP  # no volume: no hull
    assert resolve_up("-x", points, [[0, 1, 2]]) == "-x" and resolve_up("auto") == FALLBACK_UP


@pytest.mark.parametrize(
    "name, unit, expected",
    [
        ("ggg_angel_sfm.ply", "mm", "+z"),  # Z-up: the file's +z is up (it stands on its pedestal)
        ("stanford_bunny_zipper.ply", "m", "+y"),
        ("ggg_birdbath_sfm.ply", "mm", "+z"),
        ("cyberware_horse.ply", "m", "+z"),
        ("cyberware_igea.ply", "m", "+y"),  # a bust: no base, the fallback
    ],
)
def test_shared_scans_stand_the_right_way_up(name, unit, expected):
    from translucency.io import clean_mesh

    mesh, _ = clean_mesh(load_scan(name, unit))
    assert infer_up(mesh.points, mesh.triangles)[0] == expected


@pytest.mark.parametrize(
    "name, unit, expected", [("ggg_angel_sfm.ply", "mm", "+z"), ("stanford_bunny_zipper.ply", "m", "+y")]
)
def test_shared_scans_keep_their_up_when_tilted_a_little(name, unit, expected):
    from scipy.spatial.transform import Rotation

    mesh = load_scan(name, unit)
    for degrees in (3.0, 6.0):
        turn = Rotation.from_euler("xz", [degrees, 0.7 * degrees], degrees=True).as_matrix()
        assert infer_up(mesh.points @ turn.T, mesh.triangles)[0] == expected


def test_embedded_default_is_y_up():
    from translucency.app.shading.scan import load_default_scan

    mesh = load_default_scan()
    assert infer_up(mesh.points, mesh.triangles)[0] == "+y"
