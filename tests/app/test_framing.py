"""Where pictures look from (translucency.app.framing): the scan's front and a frame that holds all of it."""

import math

import numpy as np
import pytest

from translucency.app.framing import VIEW_ANGLE, framed_camera, front_direction, turned_to_front
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere


def _dumbbell():
    """Two spheres of 10 mm radius side by side along x: seen along x, one hides the other."""
    points, triangles = icosphere(3, 10.0)
    left, right = points - (15.0, 0.0, 0.0), points + (15.0, 0.0, 0.0)
    return TriangleMesh(np.vstack([left, right]), np.vstack([triangles, triangles + len(points)]))


def test_the_front_sees_both_spheres_of_a_dumbbell():
    front = front_direction(_dumbbell(), (0.0, 1.0, 0.0))
    assert abs(front[0]) < 0.5  # across the bar, not along it
    assert front[1] == pytest.approx(math.sin(math.radians(16.7)), abs=0.01)  # a little above


def test_a_scan_alike_from_everywhere_keeps_the_default_view():
    points, triangles = icosphere(3, 10.0)
    front = front_direction(TriangleMesh(points, triangles), (0.0, 1.0, 0.0))
    default = np.array([0.6, 0.35, 1.0]) / np.linalg.norm([0.6, 0.35, 1.0])
    np.testing.assert_allclose(front, default, atol=1e-9)
    np.testing.assert_allclose(turned_to_front((0.3, 0.8, 0.2), (0, 1, 0), front), (0.3, 0.8, 0.2), atol=1e-12)


def test_turning_to_the_front_keeps_the_light_where_it_was_relative_to_the_camera():
    default = np.array([0.6, 0.35, 1.0]) / np.linalg.norm([0.6, 0.35, 1.0])
    front = np.array([-default[2], default[1], default[0]])  # the default turned by 90 degrees about +y
    light = np.array([0.2, 0.9, 0.4])
    turned = turned_to_front(light, (0.0, 1.0, 0.0), front)
    assert turned @ front == pytest.approx(light @ default) and turned[1] == pytest.approx(light[1])


@pytest.mark.parametrize("aspect", [0.5, 1.0, 2.0])
def test_every_point_of_a_tall_scan_is_in_the_frame(aspect):
    rng = np.random.default_rng(3)
    points = rng.normal(size=(2000, 3)) * (10.0, 60.0, 10.0)  # a tall scan, as the angel
    direction, up = np.array([0.4, 0.3, 1.0]), np.array([0.0, 1.0, 0.0])
    eye, focus, view_up = (np.asarray(v, dtype=float) for v in framed_camera(points, direction, up, aspect))
    forward = (focus - eye) / np.linalg.norm(focus - eye)
    vertical = np.asarray(view_up) - (np.asarray(view_up) @ forward) * forward
    vertical /= np.linalg.norm(vertical)
    across = np.cross(forward, vertical)
    offsets = points - eye
    depth = offsets @ forward
    half = math.tan(math.radians(VIEW_ANGLE / 2))
    assert np.all(depth > 0)
    assert np.all(np.abs(offsets @ vertical) / depth <= half)
    assert np.all(np.abs(offsets @ across) / depth <= half * aspect)
    # and not needlessly far: some point is near the frame's edge
    fill = max(
        np.max(np.abs(offsets @ vertical) / depth) / half, np.max(np.abs(offsets @ across) / depth) / (half * aspect)
    )
    assert fill > 0.75


def test_room_below_keeps_the_bottom_of_the_picture_free():
    rng = np.random.default_rng(4)
    points = rng.normal(size=(2000, 3)) * (30.0, 20.0, 25.0)
    up = np.array([0.0, 1.0, 0.0])
    eye, focus, _ = (np.asarray(v, dtype=float) for v in framed_camera(points, (0.3, 0.2, 1.0), up, 4 / 3, 0.2))
    forward = (focus - eye) / np.linalg.norm(focus - eye)
    vertical = up - (up @ forward) * forward
    vertical /= np.linalg.norm(vertical)
    offsets = points - eye
    height = (offsets @ vertical) / (offsets @ forward) / math.tan(math.radians(VIEW_ANGLE / 2))  # -1 .. 1
    assert height.min() >= -1.0 + 2 * 0.2 - 1e-9 and height.max() <= 1.0
