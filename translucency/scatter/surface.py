"""The solver's surface: a triangle mesh as plain data, and what each algorithm keeps per surface.

:class:`SurfaceGeometry` holds the vertices, triangles and normals (mm) and the quantities that are its own
(areas, edge lengths), each computed once on first use. It holds no algorithm's work. An algorithm that
keeps work per surface (the source tree, the near field's grids and lists, relighting's operators, the
bounces' rays) owns a :class:`PerSurface` of its own: the work lives as long as the surface does, and
:func:`held_bytes` counts what the algorithms hold for a surface, for the budget.
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass, field
from functools import cached_property

import numba
import numpy as np

from ..errors import InvalidParameterError
from ..geometry.measure import barycentric_vertex_areas, longest_edges, mean_edge_length, row_lengths, triangle_areas
from ..geometry.morton import by_lowest_vertex, morton_order
from ..threads import for_ranges

__all__ = [
    "SurfaceGeometry",
    "PerSurface",
    "spatial_order",
    "ordered_light",
    "held_bytes",
    "ordered_bytes",
    "checked_array",
    "ORDER_KERNELS",
]


def checked_array(value, dtype, shape, name: str) -> np.ndarray:
    """``value`` as a C-contiguous array of ``dtype`` whose shape matches ``shape`` (``None`` = any length), or
    :class:`~translucency.errors.InvalidParameterError` naming ``name``."""
    try:
        array = np.ascontiguousarray(value, dtype=dtype)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a numeric array of shape {shape}.") from None
    if array.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, array.shape)):
        raise InvalidParameterError(
            f"{name} must have shape {tuple('n' if s is None else s for s in shape)}, got {array.shape}."
        )
    return array


@dataclass(eq=False)
class SurfaceGeometry:
    """A triangle mesh as the solver needs it: plain data, compared and hashed by identity.

    Parameters
    ----------
    points : (n, 3) float64
        Vertex positions, mm.
    triangles : (m, 3) int64
        Vertex indices of each triangle.
    normals : (n, 3) float64
        Outward unit vertex normals (rescaled to unit length where they are not).
    mean_edge_mm : float, optional
        The mean edge length (mm) when the caller has measured it already (:attr:`mean_edge_length` then takes it
        instead of measuring the edges again, a pass over every edge).
    vertex_areas_mm2 : (n,) float64, optional
        The barycentric vertex areas (mm²) when the caller holds them already (:attr:`vertex_areas` then takes them
        instead of summing the triangles again).
    ordered : bool
        Whether the vertices already lie along the Morton curve (:func:`spatial_order`'s copy).
    """

    points: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray
    mean_edge_mm: float | None = None
    vertex_areas_mm2: np.ndarray | None = field(default=None, repr=False)
    ordered: bool = False

    def __post_init__(self):
        self.points = checked_array(self.points, np.float64, (None, 3), "points")
        self.triangles = checked_array(self.triangles, np.int64, (None, 3), "triangles")
        self.normals = checked_array(self.normals, np.float64, (self.points.shape[0], 3), "normals")
        if not np.all(np.isfinite(self.points)):
            raise InvalidParameterError("points contain NaN or infinite coordinates; clean the mesh first.")
        if self.triangles.size and (self.triangles.min() < 0 or self.triangles.max() >= self.points.shape[0]):
            raise InvalidParameterError(
                f"triangles refer to vertices outside 0..{self.points.shape[0] - 1}; the mesh is corrupt."
            )
        lengths = row_lengths(self.normals)
        if not np.all(np.isfinite(lengths)):
            raise InvalidParameterError("normals contain NaN or infinite values.")
        bad = np.abs(lengths - 1.0) > 1e-6
        if np.any(bad & (lengths > 0)):
            self.normals = self.normals / np.where(lengths > 0, lengths, 1.0)[:, None]
        if self.mean_edge_mm is not None:
            self.mean_edge_mm = float(self.mean_edge_mm)
        if self.vertex_areas_mm2 is not None:
            self.vertex_areas_mm2 = checked_array(
                self.vertex_areas_mm2, np.float64, (self.points.shape[0],), "vertex_areas_mm2"
            )

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.points.shape[0])

    @cached_property
    def triangle_areas(self) -> np.ndarray:
        """Area of each triangle, mm^2."""
        return triangle_areas(self.points, self.triangles)

    @cached_property
    def vertex_areas(self) -> np.ndarray:
        """Barycentric vertex areas (one third of each adjacent triangle), mm^2.

        The solver always uses these: they make the vertex sum the three-vertex rule that the near
        field correction subtracts.
        """
        if self.vertex_areas_mm2 is not None:
            return self.vertex_areas_mm2
        return barycentric_vertex_areas(self.triangles, self.triangle_areas, self.n_vertices)

    @cached_property
    def mean_edge_length(self) -> float:
        """Mean edge length, mm."""
        if self.mean_edge_mm is not None:
            return self.mean_edge_mm
        return float(mean_edge_length(self.points, self.triangles))

    @cached_property
    def diagonal(self) -> float:
        """Length of the bounding box's diagonal, mm (measured once: every solve asks for it)."""
        return float(np.linalg.norm(np.ptp(self.points, axis=0))) if self.n_vertices else 0.0

    @cached_property
    def longest_edge(self) -> float:
        """Longest edge length, mm (0 for a mesh with no triangles)."""
        return float(longest_edges(self.points, self.triangles).max(initial=0.0))


class PerSurface:
    """What one algorithm keeps per surface: ``make()`` once per (surface, key), dropped with the surface.

    ``counted`` says whether a solve's budget counts it among what a surface holds already
    (:func:`held_bytes`); relighting's operators are not counted, since no solve's plan counts them.
    Safe to use from several threads (the viewer solves on a worker thread)."""

    _every: list[PerSurface] = []

    def __init__(self, name: str, *, counted: bool = True):
        self.name = name
        self.counted = counted
        self._held: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self._lock = threading.RLock()
        PerSurface._every.append(self)

    def get(self, surface: SurfaceGeometry, key, make):
        """The kept ``make()`` for ``surface`` and ``key``, made now if it was not."""
        with self._lock:
            kept = self._held.setdefault(surface, {})
            if key not in kept:
                kept[key] = make()
            return kept[key]

    def peek(self, surface: SurfaceGeometry, key, default=None):
        """The kept value for ``surface`` and ``key``, or ``default``; makes nothing."""
        with self._lock:
            return self._held.get(surface, {}).get(key, default)

    def drop(self, surface: SurfaceGeometry) -> None:
        """Forget everything kept for ``surface`` (its memory is freed when nothing else holds it)."""
        with self._lock:
            self._held.pop(surface, None)

    def values(self, surface: SurfaceGeometry) -> list:
        """Everything kept for ``surface``."""
        with self._lock:
            return list(self._held.get(surface, {}).values())


def _array_bytes(value, seen=None, depth: int = 4) -> int:
    """Bytes of the numpy arrays reachable from ``value`` (arrays; lists, tuples and dicts; the attributes of objects,
    ``depth`` levels down), each buffer counted once (a view counts its base)."""
    seen = set() if seen is None else seen
    if isinstance(value, np.ndarray):
        base = value
        while isinstance(base.base, np.ndarray):
            base = base.base
        if id(base) in seen:
            return 0
        seen.add(id(base))
        return int(base.nbytes)
    if depth <= 0 or isinstance(value, (str, bytes, int, float, bool, type(None))):
        return 0
    if isinstance(value, dict):
        items = value.values()
    elif isinstance(value, (list, tuple)):
        items = value
    else:
        items = list(getattr(value, "__dict__", {}).values())
        items += [getattr(value, name) for name in getattr(type(value), "__slots__", ()) if hasattr(value, name)]
    return sum(_array_bytes(item, seen, depth - 1) for item in items)


_ORDERED = PerSurface("spatial order")


def spatial_order(surface: SurfaceGeometry) -> tuple[SurfaceGeometry, np.ndarray, np.ndarray]:
    """``(ordered, order, rank)``: the same surface with its vertices along a Morton curve
    (:func:`translucency.geometry.morton.morton_order`) and its triangles by first vertex, so that neighbours sit
    close in memory whatever order the mesh came in (subdivided or merged meshes append vertices far from their
    neighbours); ``ordered.points == points[order]``, ``rank[order] == arange(n)``. The solver works on it; kept
    while ``surface`` lives (an ordered surface is its own order)."""
    if surface.ordered:
        identity = np.arange(surface.n_vertices)
        return surface, identity, identity

    def make():
        order = morton_order(surface.points)
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        known = vars(surface)  # the areas and the mean edge, where measured already: the same surface, relabelled
        areas = known.get("vertex_areas", surface.vertex_areas_mm2)
        ordered = SurfaceGeometry(
            surface.points[order],
            by_lowest_vertex(surface.triangles, order.size, relabel=rank),
            surface.normals[order],
            mean_edge_mm=known.get("mean_edge_length", surface.mean_edge_mm),
            vertex_areas_mm2=None if areas is None else areas[order],
            ordered=True,
        )
        return ordered, order, rank

    return _ORDERED.get(surface, "morton", make)


def ordered_light(phi, w12, areas, order) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The light on the spatially ordered surface (:func:`spatial_order`) in one pass: ``phi[order]`` (n, C) W/m²,
    ``w12[order]`` (n, 3), the flux ``phi[order] * areas`` (``areas``: the ordered surface's vertex areas, mm²), and
    the vertices with any flux (their indices, increasing)."""
    phi = np.ascontiguousarray(phi, dtype=np.float64)
    w12 = np.ascontiguousarray(w12, dtype=np.float64)
    out = (np.empty_like(phi), np.empty_like(w12), np.empty_like(phi), np.empty(phi.shape[0], dtype=np.bool_))
    for_ranges(_ordered_rows, phi.shape[0], phi, w12, np.ascontiguousarray(areas, dtype=np.float64), order, *out)
    return out[0], out[1], out[2], np.flatnonzero(out[3])


@numba.njit(cache=True, nogil=True)
def _ordered_rows(worker, lo, hi, phi, w12, areas, order, phi_out, w12_out, flux, lit):
    """Rows ``lo .. hi - 1`` of :func:`ordered_light`."""
    for i in range(lo, hi):
        j = order[i]
        lit[i] = False
        for c in range(phi.shape[1]):
            phi_out[i, c] = phi[j, c]
            flux[i, c] = phi[j, c] * areas[i]
            lit[i] = lit[i] or flux[i, c] > 0.0
        for k in range(3):
            w12_out[i, k] = w12[j, k]


def held_bytes(surface: SurfaceGeometry) -> int:
    """Bytes of the surface's own arrays and of what the algorithms keep for it, counted ones only
    (:class:`PerSurface`)."""
    held = list(vars(surface).values())
    for part in PerSurface._every:
        if part.counted:
            held += part.values(surface)
    return _array_bytes(held)


def ordered_bytes(surface: SurfaceGeometry) -> int:
    """Bytes held by the spatially ordered copy of ``surface`` and what the algorithms keep for it (the source tree,
    triangle tables, near grids and lists; not relighting's operators, which no solve's plan counts) when it is made
    already, else 0: what a solve's plan counts as still to be made."""
    held = _ORDERED.peek(surface, "morton")
    if held is None:
        return 0
    ordered, order, rank = held
    return held_bytes(ordered) + _array_bytes([order, rank])


#: The compiled kernel of the light's move onto the ordered surface: numba compiles it on first use; the set-up
#: compiles it ahead (:mod:`translucency.app.warmup`).
ORDER_KERNELS = (_ordered_rows,)
