"""Which way is up: a scan's up axis, given or inferred, and the display frame built on it.

Scan files do not say which axis points up: scanning repositories and glTF use +y, photogrammetry,
CAD and 3D printing mostly +z. The solver does not care (lights are given in the scan's own frame);
the display does: the camera's view-up, the side it looks from, and the default light, which is
placed above and in front of the scan.

``auto`` (:func:`infer_up`) looks for the side the object stands on, a flat and stable base:

1. For each of the six axis directions ``d`` the *base* toward ``d`` is the part of the convex hull
   of the vertices whose facets have outward normals within :data:`BASE_ANGLE` of ``d``: the plane
   the object would rest on if set down on that side (a stand, a pedestal, four hooves; a base left
   open by the scanner has the same hull).
2. Its *stability margin* is how far the surface's centroid (area-weighted), seen along ``d``, lies
   inside the base polygon, over the square root of the polygon's area; it is negative when the
   centroid lies outside, where the object would topple.
3. The score of a side is (base polygon area / hull area) x margin. The side with the highest score
   is down when that score is at least :data:`MIN_SCORE`; with no such side (a bust cut at the neck,
   a single-view range scan) up is :data:`FALLBACK_UP`, the convention of scanning repositories;
   equal scores (a cube) are decided in the order of :data:`TIE_ORDER`.

On scans of objects that stand (a pedestal, hooves, a flat bottom) the best side scores several times
:data:`MIN_SCORE`; a bust or a single-view range scan has no side that reaches it and falls back. Turning a
scan by a few degrees leaves the answer as it was (facets within :data:`BASE_ANGLE` of the axis still make
the base).
The cost is one convex hull of the vertices; on a large scan the hull is built only from the points that
the polytope of 64 extreme points does not contain (:func:`~translucency.geometry.measure.hull_candidates`).

The display frame (:func:`display_frame`) maps the scan's axes to right, up and front (a right-handed
frame): for ``+y`` it is the identity (front +z), for ``+z`` front is -y (the "front view" of Z-up
tools), and so on (:data:`FRONT`); the default camera and light are given in that frame.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, option
from ..geometry.measure import area_centroids, hull_candidates

__all__ = [
    "UP_CHOICES",
    "AXES",
    "FRONT",
    "BASE_ANGLE",
    "MIN_SCORE",
    "FALLBACK_UP",
    "parse_up",
    "up_vector",
    "base_scores",
    "infer_up",
    "resolve_up",
    "display_frame",
    "to_scan_frame",
]

#: The six axis directions, as ``--up`` takes them.
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")
#: What ``--up`` / ``up=`` accept: an axis (``x`` means ``+x``) or ``auto``.
UP_CHOICES = ("x", "y", "z", "-x", "-y", "-z", "auto")
#: Hull facets within this angle (degrees) of an axis direction make the base on that side.
BASE_ANGLE = 8.0
#: Smallest score (base area fraction x stability margin) that counts as a base.
MIN_SCORE = 0.005
#: Up when no side is a base.
FALLBACK_UP = "+y"
#: Down sides in the order that breaks a tie of equal scores (+y up, then +z up, first).
TIE_ORDER = ("-y", "-z", "-x", "+y", "+z", "+x")
#: The front (the side the default camera and light look from) for each up axis: with right = up x
#: front, (right, up, front) is right-handed, and +y up gives the identity frame.
FRONT = {"+y": "+z", "-y": "-z", "+z": "-y", "-z": "+y", "+x": "+z", "-x": "+z"}


def parse_up(up) -> str:
    """``"+x"`` ... ``"-z"`` or ``"auto"`` from what a user typed (``"y"``, ``"+Y"``, ``"-z"``, ``"auto"``).

    Raises
    ------
    InvalidParameterError
        For anything else, naming the choices.
    """
    text = str(up).strip().lower() if isinstance(up, str) else None
    if text == "auto":
        return "auto"
    if text is not None and text.lstrip("+-") in ("x", "y", "z") and len(text) <= 2:
        return text if text[0] in "+-" else "+" + text
    raise InvalidParameterError(
        f"the up axis must be one of {', '.join(UP_CHOICES)}, got {up!r}; pass e.g. {option('up', 'z')}."
    )


def up_vector(axis: str) -> np.ndarray:
    """Unit vector of an axis direction ``"+x"`` ... ``"-z"``, float64 (3,)."""
    vector = np.zeros(3)
    vector["xyz".index(axis[1])] = 1.0 if axis[0] == "+" else -1.0
    return vector


#: The most points whose convex hull the base rule takes: a convex object (a sphere) has every vertex on its hull,
#: and qhull on 3M of them took 37 s and 1.2 GB; an even share along the file's order (its points are mostly in
#: surface order) gives the hull of a scan to within its sampling, and the scores are ratios of its areas.
HULL_POINTS = 100_000


def _axis_name(index: int, sign: float) -> str:
    return ("+" if sign > 0 else "-") + "xyz"[index]


def base_scores(points, triangles) -> dict:
    """Score of each side as a base (module docstring): ``{"-y": 0.043, ...}``; None where there is no base.

    Parameters
    ----------
    points : (n, 3) array_like
        Vertex positions (any unit: the scores are ratios).
    triangles : (m, 3) array_like of int
        Triangles; only the vertices they use count.

    Returns
    -------
    dict of str to float or None
        Keyed by the *down* direction (``"-y"``: the object stands on its lowest y).
    """
    from scipy.spatial import ConvexHull, QhullError

    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    area, centroid = area_centroids(points, triangles)
    scores = {axis: None for axis in AXES}
    if not area[0] > 0:
        return scores
    centroid = centroid[0]
    in_use = np.zeros(points.shape[0], dtype=bool)
    in_use[triangles.ravel()] = True
    try:
        used = hull_candidates(points if in_use.all() else points[in_use])  # a cleaned scan uses every vertex
        if len(used) > HULL_POINTS:  # a convex scan keeps every point: the hull of an even share of them
            used = used[np.linspace(0, len(used) - 1, HULL_POINTS).astype(np.int64)]
        hull = ConvexHull(used)
    except (QhullError, ValueError):  # flat or too few points: no volume, no base
        return scores
    cos_limit = np.cos(np.radians(BASE_ANGLE))
    for index in range(3):
        others = [k for k in range(3) if k != index]
        for sign in (1.0, -1.0):
            facing = sign * hull.equations[:, index] > cos_limit
            if not facing.any():
                continue
            base = used[np.unique(hull.simplices[facing])][:, others]
            try:
                polygon = ConvexHull(base)
            except (QhullError, ValueError):
                continue
            # inside distance of the centroid to each edge (qhull's equations: n . x + offset <= 0 inside)
            margin = float(np.min(-(polygon.equations[:, :2] @ centroid[others] + polygon.equations[:, 2])))
            margin /= np.sqrt(polygon.volume)  # a 2-D hull's "volume" is its area
            scores[_axis_name(index, sign)] = float(polygon.volume / hull.area * margin)
    return scores


def infer_up(points, triangles) -> tuple[str, str]:
    """The up axis of a scan by the flat, stable base rule (module docstring).

    Parameters
    ----------
    points : (n, 3) array_like
        Vertex positions (any unit).
    triangles : (m, 3) array_like of int

    Returns
    -------
    up : str
        ``"+x"`` ... ``"-z"``.
    reason : str
        A few words on why (``"it stands on its lowest y"``, or that no base was found).
    """
    scores = {axis: score for axis, score in base_scores(points, triangles).items() if score is not None}
    if scores:
        best = max(scores.values())
        # equal scores (a cube): the first of the conventions, +y up, then +z up
        down = next(axis for axis in TIE_ORDER if axis in scores and scores[axis] >= best - 1e-9 * abs(best))
        if scores[down] >= MIN_SCORE:
            up = ("+" if down[0] == "-" else "-") + down[1]
            side = "lowest" if down[0] == "-" else "highest"
            return up, f"it stands on a flat base at its {side} {down[1]}"
    return FALLBACK_UP, f"no flat, stable base found; {FALLBACK_UP} is the common convention"


def resolve_up(up, points=None, triangles=None) -> str:
    """An up axis ``"+x"`` ... ``"-z"`` from what was asked: an axis, or ``"auto"`` (inferred from the mesh).

    Parameters
    ----------
    up : str
        ``"auto"``, ``"x"``, ``"-z"``, ... (see :func:`parse_up`).
    points, triangles : array_like, optional
        The mesh, needed for ``"auto"``.
    """
    up = parse_up(up)
    if up != "auto":
        return up
    if points is None or triangles is None:
        return FALLBACK_UP
    return infer_up(points, triangles)[0]


def display_frame(up: str) -> np.ndarray:
    """Rows right, up, front of the display frame, in the scan's coordinates: a (3, 3) rotation.

    ``display_frame(up) @ v`` turns a scan-frame vector into display coordinates (x right, y up,
    z toward the front); ``display_frame(up).T @ v`` turns a display-frame vector into the scan's.
    """
    up_axis = up_vector(parse_up(up))
    front = up_vector(FRONT[parse_up(up)])
    return np.stack([np.cross(up_axis, front), up_axis, front])


def to_scan_frame(direction, up: str) -> np.ndarray:
    """A direction given in the display frame (x right, y up, z front) in the scan's coordinates."""
    return display_frame(up).T @ np.asarray(direction, dtype=np.float64)
