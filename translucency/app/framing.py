"""Where a picture's camera stands: the scan's front, and a distance at which the whole scan is in view.

Every picture of a scan uses it: the viewer, ``view --screenshot``, bake previews and compare grids.

**The front.** The camera looks from :data:`FRONT_ELEVATION` degrees above the plane across the scan's up
axis, from the azimuth (one of :data:`FRONT_AZIMUTHS` around it, starting at the default direction's) that
sees the most surface: the area of the triangles that face the camera and that nothing of the scan hides
from it, counted with Embree rays from their centres. Surface seen at a slant counts fully, so a side that
shows more of the scan (a horse's flank, a face rather than the back of a head) wins over one that shows
only its outline. Among azimuths within :data:`FRONT_TIE` of the best, the one nearest the package's
default direction (:func:`default_camera_direction`, front right) is taken, so
that a scan that looks the same from everywhere keeps the usual view.

**The distance.** The scan's points are projected on the view's axes; the camera stands back along the view
direction until the projection, widened by :data:`FRAME_MARGIN`, fits the vertical view angle
(:data:`VIEW_ANGLE`, PyVista's default) and the picture's width, with the near half of the scan's depth
added (perspective makes it larger than its projection).
"""

from __future__ import annotations

import math

import numpy as np

#: Default camera: looking at the mesh's centre from this direction of the display frame (right, up,
#: front; :func:`translucency.io.upright.display_frame`): from the front, a little from the right and
#: above. For a scan whose up is +y (the default bunny) it is the direction in the scan's coordinates.
DEFAULT_CAMERA_DIRECTION = (0.6, 0.35, 1.0)
#: View-up vector of the camera for a scan whose up is +y.
DEFAULT_UP = (0.0, 1.0, 0.0)
#: Camera distance from the centre, in bounding-box diagonals.
CAMERA_DISTANCE = 1.7


def default_camera_direction(up: str = "+y") -> np.ndarray:
    """:data:`DEFAULT_CAMERA_DIRECTION` in the scan's coordinates for an up axis ``"+x"`` ... ``"-z"``."""
    from ..io.upright import to_scan_frame

    return to_scan_frame(DEFAULT_CAMERA_DIRECTION, up)


def camera_position(center, diagonal, direction=DEFAULT_CAMERA_DIRECTION, up=DEFAULT_UP) -> list:
    """PyVista camera position looking at ``center`` from ``direction``.

    Parameters
    ----------
    center : sequence of 3 float
        Focal point, mm.
    diagonal : float
        Size of the object (bounding-box diagonal), mm; the eye is :data:`CAMERA_DISTANCE` of it away.
    direction : sequence of 3 float
        From the focal point toward the eye (any non-zero length).
    up : sequence of 3 float
        View-up vector.

    Returns
    -------
    list
        ``[eye, focal point, view up]``, as ``plotter.camera_position`` takes it.
    """
    center = np.asarray(center, dtype=float)
    direction = np.asarray(direction, dtype=float)
    direction = direction / np.linalg.norm(direction)
    return [tuple(center + direction * CAMERA_DISTANCE * float(diagonal)), tuple(center), tuple(float(u) for u in up)]


#: Azimuths tried for the front (evenly around the up axis).
FRONT_AZIMUTHS = 24
#: Elevation of the camera above the plane across the up axis, degrees (that of the default direction).
FRONT_ELEVATION = math.degrees(
    math.asin(DEFAULT_CAMERA_DIRECTION[1] / math.sqrt(sum(c * c for c in DEFAULT_CAMERA_DIRECTION)))
)
#: Triangles sampled (by area) to measure the surface seen from an azimuth.
FRONT_SAMPLES = 8000
#: Azimuths seeing at least this fraction of the best are tied; the one nearest the default direction wins.
FRONT_TIE = 0.97
#: Vertical view angle of the camera, degrees.
VIEW_ANGLE = 30.0
#: The projected scan is framed with this much room around it (a factor on its half extents).
FRAME_MARGIN = 1.06
#: PyVista's own window (``plot()``'s default), width over height, and the share of its height its default
#: colour bar and labels take at the bottom: what :meth:`ShadeResult.camera_position
#: <translucency.app.shading.result.ShadeResult.camera_position>` frames for.
PYVISTA_ASPECT, PYVISTA_BAR_ROOM = 1024 / 768, 0.2


def frame_axes(up):
    """Unit ``up`` and two unit axes ``e1, e2`` across it (``e1``: +z made perpendicular to ``up``, or +x when
    ``up`` is near z; ``e2 = up x e1``): the frame of azimuths and elevations around ``up``."""
    up = np.asarray(up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    seed = np.array([0.0, 0.0, 1.0]) if abs(up[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = seed - (seed @ up) * up
    e1 /= np.linalg.norm(e1)
    return up, e1, np.cross(up, e1)


def front_direction(mesh, up) -> np.ndarray:
    """Unit direction from the scan's centre toward the camera that sees its front (module docstring).

    Parameters
    ----------
    mesh : TriangleMesh
        The scan, mm.
    up : sequence of 3 float
        The scan's up axis (its coordinates).
    """
    from ..scatter.visibility import Occluder

    up, e1, e2 = frame_axes(up)
    points, triangles = mesh.points, mesh.triangles
    corners = points[triangles]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    doubled = np.linalg.norm(cross, axis=1)
    keep = doubled > 0
    if not keep.any():
        return DEFAULT_CAMERA_DIRECTION / np.linalg.norm(DEFAULT_CAMERA_DIRECTION)
    corners, cross, doubled = corners[keep], cross[keep], doubled[keep]
    normals = cross / doubled[:, None]
    centres = corners.mean(axis=1)
    area = 0.5 * doubled
    if len(area) > FRONT_SAMPLES:  # a sample of triangles, by area; each then stands for the same area
        rng = np.random.default_rng(0)
        pick = rng.choice(len(area), FRONT_SAMPLES, p=area / area.sum())
        centres, normals, area = centres[pick], normals[pick], np.full(FRONT_SAMPLES, area.sum() / FRONT_SAMPLES)
    occluder = Occluder(points, triangles, workers=1)
    elevation = math.radians(FRONT_ELEVATION)
    default = _default_in_frame(up)
    start = math.atan2(float(default @ e2), float(default @ e1))  # the default's own azimuth is the first tried
    seen, directions = [], []
    for k in range(FRONT_AZIMUTHS):
        azimuth = start + 2.0 * math.pi * k / FRONT_AZIMUTHS
        d = math.cos(elevation) * (math.cos(azimuth) * e1 + math.sin(azimuth) * e2) + math.sin(elevation) * up
        facing = np.flatnonzero(normals @ d > 0.0)
        visible = occluder.visible(centres[facing], normals[facing], d)
        seen.append(float(area[facing][visible].sum()))
        directions.append(d)
    seen, directions = np.asarray(seen), np.asarray(directions)
    tied = np.flatnonzero(seen >= FRONT_TIE * seen.max())
    return directions[tied[np.argmax(directions[tied] @ default)]]


def turned_to_front(vector, up, front) -> np.ndarray:
    """``vector`` turned about ``up`` by the azimuth that takes the default camera direction to ``front``: a light
    placed relative to the default view keeps its place relative to the front view."""
    up_unit, e1, e2 = frame_axes(up)
    default = _default_in_frame(up)
    angle = math.atan2(float(front @ e2), float(front @ e1)) - math.atan2(float(default @ e2), float(default @ e1))
    v = np.asarray(vector, dtype=np.float64)
    along = (v @ up_unit) * up_unit
    across = v - along
    # Rodrigues' rotation about the unit axis up: across cos + (up x across) sin
    return along + math.cos(angle) * across + math.sin(angle) * np.cross(up_unit, across)


def _default_in_frame(up) -> np.ndarray:
    """The default camera direction (front right, above) for a scan whose up axis is ``up``: that of
    :func:`default_camera_direction` for a coordinate axis, else the same angles in
    :func:`frame_axes`' frame."""
    from ..io.upright import up_vector

    up = np.asarray(up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    for axis in ("+x", "-x", "+y", "-y", "+z", "-z"):
        if np.allclose(up_vector(axis), up):
            d = np.asarray(default_camera_direction(axis), dtype=np.float64)
            return d / np.linalg.norm(d)
    _, e1, e2 = frame_axes(up)
    d = np.asarray(DEFAULT_CAMERA_DIRECTION, dtype=np.float64)
    d = d / np.linalg.norm(d)
    # DEFAULT_CAMERA_DIRECTION is written for +y up: its z is e1's part and its x is e2's
    return d[2] * e1 + d[0] * e2 + d[1] * up


def framed_camera(points, direction, up, aspect: float = 1.0, room_below: float = 0.0) -> list:
    """PyVista camera position ``[eye, focal point, view up]`` that shows every point from ``direction``.

    Parameters
    ----------
    points : (n, 3) float
        The scan's points, mm.
    direction : sequence of 3 float
        From the scan toward the camera (any non-zero length).
    up : sequence of 3 float
        View-up (the camera makes it perpendicular to ``direction``).
    aspect : float
        The picture's width over its height.
    room_below : float
        Share of the picture's height left empty under the scan (for a colour bar there), 0 to 0.5.
    """
    points = np.asarray(points, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    view_up = np.asarray(up, dtype=np.float64) - (np.asarray(up, dtype=np.float64) @ d) * d
    if np.linalg.norm(view_up) < 1e-9:  # looking along up: any perpendicular will do
        view_up = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    view_up /= np.linalg.norm(view_up)
    right = np.cross(d, view_up)
    low, high = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (low + high)
    offsets = points - centre
    u, v, w = offsets @ right, offsets @ view_up, offsets @ d
    room_below = min(max(float(room_below), 0.0), 0.5)
    half_width = FRAME_MARGIN * 0.5 * float(u.max() - u.min())
    half_height = FRAME_MARGIN * 0.5 * float(v.max() - v.min()) / (1.0 - room_below)
    # focal point at the middle of the projection across, and below its middle by the room left under it, so the
    # scan sits in the middle of the picture (or above the room)
    vertical = 0.5 * (v.max() + v.min()) - room_below * half_height
    centre = centre + 0.5 * (u.max() + u.min()) * right + vertical * view_up
    tangent = math.tan(math.radians(0.5 * VIEW_ANGLE))
    distance = max(half_height / tangent, half_width / (tangent * max(aspect, 1e-3)), 1e-6) + float(w.max())
    return [tuple(centre + distance * d), tuple(centre), tuple(float(u) for u in up)]


def scan_camera(mesh, up, aspect: float = 1.0, direction=None, room_below: float = 0.0) -> list:
    """The camera position of every picture of a scan: from its front (or ``direction``), the whole scan framed
    (:func:`framed_camera`)."""
    if direction is None:
        direction = front_direction(mesh, up)
    return framed_camera(mesh.points, direction, up, aspect, room_below)
