"""Near-field surface integration: the part of B(x_o) that a vertex sum gets wrong.

The solver's answer is the surface integral ``B(x_o) = integral S_d(x, w12(x); x_o) phi(x) dA(x)``
(DESIGN.md, "Fast and accurate"). Summing over vertices, ``sum_j S_d(x_j; x_o) phi_j A_j``, is the
integral with a three-vertex rule on every triangle (``A_j`` is one third of the adjacent triangle
areas). That rule is accurate for triangles far from ``x_o`` compared with their size and with the
diffusion coefficient ``D`` -- and badly wrong near ``x_o``, where ``S_d`` varies on the scale ``D``
(0.1-0.5 mm for real materials) and the self term ``S_d(x_o; x_o)`` is counted with a whole vertex
area. So, for every receiver, the triangles within a near radius get a correction::

    C(x_o) = sum_{T near x_o} [ Q_T(f) - (A_T / 3) sum_{k in T} f(x_k) ],   f = S_d(.; x_o) phi

where ``Q_T`` is a quadrature over the triangle chosen by its distance to ``x_o``:

* the receiver's own triangles (``x_o`` at a corner, where ``S_d`` peaks on the scale ``D``): the
  fan rule of :func:`fan_rule`, Gauss-Legendre in the polar angle about ``x_o`` and in ``log(1 + r / c)``
  along each ray;
* triangles too close to be integrated whole (diameter ``h > beta * max(dist, D_min)``, ``dist`` from
  ``x_o`` to the centroid): midpoint subdivision into four until every piece passes that test, then
  the 7-point degree-5 rule of Dunavant (1985) on each piece;
* whole triangles: Dunavant's rule, or -- farther than ``h / degree3_ratio`` -- the degree-3 rule on
  corners, edge midpoints and centroid, whose midpoints two triangles share.

Position, normal and flux density are interpolated linearly over the triangle (the normal
renormalised), the refracted direction flux-weighted. ``B = vertex sum + C`` is then the surface
integral, whatever the tessellation.

=========== ============================================================= ===========
symbol      meaning                                                       unit
=========== ============================================================= ===========
phi         incident flux density after the boundary (T12 E cos V)        flux / mm^2
A_T         triangle area                                                 mm^2
beta        refinement ratio (piece diameter over distance)               1
D_min       smallest diffusion coefficient over the channels              mm
=========== ============================================================= ===========
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from ..geometry.measure import longest_edges, triangle_centroids
from ..geometry.topology import corner_edge_numbers, corner_starts, index_dtype, kernel_array
from ..threads import for_ranges, thread_count
from .fits import QUADRATIC_TERMS, fitted_points, run_scratch
from .kernels import channel_lanes, indexed_sum
from .surface import PerSurface
from .treewalk import GROUP_RECEIVERS, group_spheres

# Dunavant (1985) 7-point rule, exact for polynomials of degree 5: barycentric points and weights
# (weights sum to 1; multiply by the area).
_A1, _B1 = 0.059715871789770, 0.470142064105115
_A2, _B2 = 0.797426985353087, 0.101286507323456
_W1, _W2 = 0.132394152788506, 0.125939180544827
RULE_POINTS = np.array(
    [
        [1 / 3, 1 / 3, 1 / 3],
        [_A1, _B1, _B1],
        [_B1, _A1, _B1],
        [_B1, _B1, _A1],
        [_A2, _B2, _B2],
        [_B2, _A2, _B2],
        [_B2, _B2, _A2],
    ]
)
RULE_WEIGHTS = np.array([0.225, _W1, _W1, _W1, _W2, _W2, _W2])

MAX_DEPTH = 14  # pieces as small as 4^-14 of the triangle's area


def gauss_legendre_unit(n):
    """``n`` Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


#: Fan rule over the receiver's own triangles: Gauss-Legendre nodes across the fan (angular, per sector)
#: and along each ray (radial, per stretch); see :func:`fan_rule`.
FAN_ANGULAR = 3
FAN_RADIAL = 5


@dataclass
class NearGrid:
    """What listing near triangles needs once per (mesh, radius): the vertices binned in a grid of cells at
    least ``radius`` wide, each vertex's triangles (CSR) and one stamp per triangle and thread; built by
    :func:`near_grid`. :meth:`lists` and :meth:`counts` serve any number of blocks of receivers (the stamps
    carry on, so a block never mistakes an earlier block's for its own).

    Attributes
    ----------
    args : tuple
        The arguments of ``_near_pass`` that do not depend on the receivers.
    radius : float
        mm.
    n_triangles : int
    stamps : (threads, m) int32
    next_stamp : int
        The first stamp the next pass may use (the stamps start again from -1 before it would pass int32's
        largest).
    """

    args: tuple
    radius: float
    n_triangles: int
    stamps: np.ndarray
    next_stamp: int = 0

    def lists(self, receivers, counts=None):
        """For each receiver vertex, the triangles that have a vertex within the radius of it (its own 1-ring
        included): ``(offsets, triangle_ids)``, as :func:`near_triangles` returns them. ``counts``: the receivers'
        :meth:`counts`, where the caller has them (else counted here, a pass of its own)."""
        if counts is None:
            counts = self.counts(receivers)
        offsets = np.zeros(counts.size + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        triangle_ids = np.empty(offsets[-1], dtype=index_dtype(self.n_triangles))
        self._pass(receivers, offsets, triangle_ids, counts)
        return offsets, triangle_ids

    def counts(self, receivers):
        """Number of near triangles of each receiver, ``(n_receivers,)`` int64 (:meth:`lists` without them)."""
        counts = np.zeros(len(receivers), dtype=np.int64)
        self._pass(receivers, np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int32), counts)
        return counts

    def _pass(self, receivers, offsets, triangle_ids, counts):
        """One pass of ``_near_pass`` (count when ``triangle_ids`` is empty, else fill) with fresh stamps."""
        receivers = np.ascontiguousarray(receivers, dtype=np.int64)
        points, sorted_points, low, cell, dims, cell_keys = self.args[:6]
        visit = np.argsort(_cell_keys(points[receivers], low, cell, dims), kind="stable")  # cell by cell
        if self.next_stamp + receivers.size >= np.iinfo(self.stamps.dtype).max:
            self.stamps.fill(-1)
            self.next_stamp = 0
        base = self.next_stamp
        self.next_stamp += receivers.size
        for_ranges(
            _near_pass,
            receivers.size,
            points,
            sorted_points,
            receivers,
            visit,
            self.radius,
            *self.args[2:],
            offsets,
            triangle_ids,
            counts,
            self.stamps,
            base,
        )


def near_grid(points, triangles, radius) -> NearGrid:
    """The :class:`NearGrid` of a mesh (mm) for ``radius`` (mm): O(n log n) once, for every block after."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    n = points.shape[0]
    # vertex -> incident triangles (CSR); numbers of vertices, triangles and corners and the stamps as int32 where
    # they fit: with the sorted points they are most of the grid
    vt_offsets, vt_tris = _vertex_triangles(
        triangles,
        n,
        np.zeros(1, dtype=index_dtype(3 * triangles.shape[0])),
        np.zeros(1, dtype=index_dtype(triangles.shape[0])),
    )
    # the grid: cells keyed by their integer coordinates, vertices sorted by key
    low = points.min(axis=0) if n else np.zeros(3)
    extent = float(np.ptp(points, axis=0).max()) if n else 0.0
    cell = max(float(radius), extent * 1e-6, 1e-300)  # at most 1e6 cells a side: keys fit in int64
    dims = (np.floor((points.max(axis=0) - low) / cell).astype(np.int64) + 1) if n else np.ones(3, dtype=np.int64)
    keys = _cell_keys(points, low, cell, dims)
    by_key = np.argsort(keys, kind="stable")
    sorted_keys = keys[by_key]
    cell_start = np.flatnonzero(np.diff(sorted_keys, prepend=-1)).astype(np.int64)  # where a cell's run begins
    cell_keys = sorted_keys[cell_start]
    cell_start = np.append(cell_start, n)
    args = (
        points,
        np.ascontiguousarray(points[by_key]),
        low,
        cell,
        dims,
        cell_keys,
        cell_start,
        by_key.astype(index_dtype(n)),
        vt_offsets,
        vt_tris,
    )
    stamps = np.full((thread_count(), triangles.shape[0]), -1, dtype=np.int32)
    return NearGrid(args, float(radius), int(triangles.shape[0]), stamps)


@numba.njit(cache=True, nogil=True)
def _vertex_triangles(triangles, n, like_offsets, like_triangles):
    """The triangles at each of ``n`` vertices, by counting (CSR ``(offsets (n + 1,), triangles)`` in the types of
    the ``like_`` arrays): a vertex's in increasing order, a triangle once per corner at the vertex."""
    offsets = corner_starts(triangles, n, like_offsets)
    fill = offsets[:-1].copy()
    out = np.empty(3 * triangles.shape[0], dtype=like_triangles.dtype)
    for t in range(triangles.shape[0]):
        for c in range(3):
            v = triangles[t, c]
            out[fill[v]] = t
            fill[v] += 1
    return offsets, out


def near_triangles(points, triangles, receivers, radius):
    """For each receiver vertex, the triangles that have a vertex within ``radius`` (mm) of it.

    Includes the receiver's own 1-ring (the receiver is within any radius of itself). The vertices
    are binned in a uniform grid of cells at least ``radius`` wide (:func:`near_grid`; keep the grid and call
    its :meth:`NearGrid.lists` to list blocks of receivers one at a time), and each receiver looks at the 27
    cells around its own, in parallel (two passes: count, then fill).

    Returns
    -------
    offsets : (n_receivers + 1,) int64
    triangle_ids : (offsets[-1],) int32 (int64 for meshes of 2**31 triangles or more)
        CSR lists: the near triangles of receiver ``r`` are ``triangle_ids[offsets[r]:offsets[r+1]]``. They
        are the largest arrays of a solve (an entry per near triangle of every receiver), hence 4 bytes.
    """
    return near_grid(points, triangles, radius).lists(receivers)


def _cell_keys(points, low, cell, dims):
    """Grid key ``(i * dims[1] + j) * dims[2] + k`` of each point's cell."""
    ijk = np.minimum(((points - low) / cell).astype(np.int64), dims - 1)
    return (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _near_pass(
    worker,
    lo,
    hi,
    points,
    sorted_points,
    receivers,
    visit,
    radius,
    low,
    cell,
    dims,
    cell_keys,
    cell_start,
    by_key,
    vt_offsets,
    vt_tris,
    offsets,
    triangle_ids,
    counts,
    stamps,
    stamp_base,
):
    """Count (``triangle_ids`` empty) or write each receiver's near triangles, each once, receivers in
    the order ``visit``: ``stamps`` (threads x triangles) hold the stamp ``stamp_base + receiver`` of the
    receiver that last took one. ``sorted_points`` are the points cell by cell (``points[by_key]``), so
    that a cell's distance checks read contiguous memory. Receivers ``visit[lo:hi]``; ``worker`` picks the
    row of ``stamps`` (:func:`~translucency.threads.for_ranges`)."""
    write = triangle_ids.shape[0] > 0
    r2 = radius * radius
    mine = stamps[worker]
    for p in range(lo, hi):
        q = visit[p]
        me = stamp_base + q
        x = points[receivers[q]]
        ci = min(int((x[0] - low[0]) / cell), dims[0] - 1)
        cj = min(int((x[1] - low[1]) / cell), dims[1] - 1)
        ck = min(int((x[2] - low[2]) / cell), dims[2] - 1)
        at = offsets[q] if write else 0
        count = 0
        k_lo = max(ck - 1, 0)
        k_hi = min(ck + 1, dims[2] - 1)
        for i in range(max(ci - 1, 0), min(ci + 2, dims[0])):
            for j in range(max(cj - 1, 0), min(cj + 2, dims[1])):
                # the cells (i, j, k_lo..k_hi) have consecutive keys: one search, then walk
                last = (i * dims[1] + j) * dims[2] + k_hi
                c = np.searchsorted(cell_keys, last - (k_hi - k_lo))
                while c < cell_keys.shape[0] and cell_keys[c] <= last:
                    for s in range(cell_start[c], cell_start[c + 1]):
                        d2 = (
                            (sorted_points[s, 0] - x[0]) ** 2
                            + (sorted_points[s, 1] - x[1]) ** 2
                            + (sorted_points[s, 2] - x[2]) ** 2
                        )
                        if d2 > r2:
                            continue
                        v = by_key[s]
                        for e in range(vt_offsets[v], vt_offsets[v + 1]):
                            t = vt_tris[e]
                            if mine[t] != me:
                                mine[t] = me
                                if write:
                                    triangle_ids[at] = t
                                    at += 1
                                count += 1
                    c += 1
        counts[q] = count


@numba.njit(cache=True, inline="always")
def corner_flux(phi, a, b, c):
    """The flux ``phi`` summed over the channels at the vertices ``a, b, c``: the weights of their refracted
    directions where :func:`gather_point` interpolates the direction."""
    fa = 0.0
    fb = 0.0
    fc = 0.0
    for ch in range(phi.shape[1]):
        fa += phi[a, ch]
        fb += phi[b, ch]
        fc += phi[c, ch]
    return fa, fb, fc


@numba.njit(cache=True, fastmath=True)
def gather_point(points, normals, w12, phi, tri, b0, b1, b2, weight, buf, weights, column):
    """Write the point with barycentric ``b`` of triangle ``tri`` to column ``column`` of the buffer.

    ``buf[:, column]`` = position (3), normal (3, renormalised), refracted direction (3, flux-weighted
    and renormalised); ``weights[c, column] = weight * phi_c(b)`` (phi interpolated linearly). Where
    no light enters, the weights are 0 and the point is a harmless copy of the first corner (normal
    ``n``, direction ``-n``), so that evaluating it gives a finite 0.
    """
    a, b, c = tri[0], tri[1], tri[2]
    n_out = phi.shape[1]
    fa, fb, fc = corner_flux(phi, a, b, c)
    wa = b0 * fa
    wb = b1 * fb
    wc = b2 * fc
    v0 = wa * w12[a, 0] + wb * w12[b, 0] + wc * w12[c, 0]
    v1 = wa * w12[a, 1] + wb * w12[b, 1] + wc * w12[c, 1]
    v2 = wa * w12[a, 2] + wb * w12[b, 2] + wc * w12[c, 2]
    vn = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    m0 = b0 * normals[a, 0] + b1 * normals[b, 0] + b2 * normals[c, 0]
    m1 = b0 * normals[a, 1] + b1 * normals[b, 1] + b2 * normals[c, 1]
    m2 = b0 * normals[a, 2] + b1 * normals[b, 2] + b2 * normals[c, 2]
    mn = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    if mn <= 0.0:
        m0, m1, m2, mn = 0.0, 0.0, 1.0, 1.0
    if wa + wb + wc <= 0.0 or vn <= 0.0:  # no light enters here
        for i in range(3):
            buf[i, column] = points[a, i]
        buf[3, column] = m0 / mn
        buf[4, column] = m1 / mn
        buf[5, column] = m2 / mn
        buf[6, column] = -m0 / mn
        buf[7, column] = -m1 / mn
        buf[8, column] = -m2 / mn
        for ch in range(n_out):
            weights[ch, column] = 0.0
        return
    for i in range(3):
        buf[i, column] = b0 * points[a, i] + b1 * points[b, i] + b2 * points[c, i]
    buf[3, column] = m0 / mn
    buf[4, column] = m1 / mn
    buf[5, column] = m2 / mn
    buf[6, column] = v0 / vn
    buf[7, column] = v1 / vn
    buf[8, column] = v2 / vn
    for ch in range(n_out):
        weights[ch, column] = weight * (b0 * phi[a, ch] + b1 * phi[b, ch] + b2 * phi[c, ch])


#: Degree-3 rule (Strang & Fix 1973) on the corners, edge midpoints and centroid: weights (sum 1,
#: multiply by the area). Its midpoints are shared by the two triangles of an edge, its corners by the
#: vertex rule and its centroid is the first of Dunavant's points (already in the shared table), so a
#: triangle costs a receiver about 2.5 evaluations instead of the 7 of Dunavant's rule.
CORNER_WEIGHT, MIDPOINT_WEIGHT, CENTROID_WEIGHT = 1.0 / 20.0, 2.0 / 15.0, 9.0 / 20.0


@dataclass
class SourcePoints:
    """Quadrature points every receiver shares (columns of ``table``; see :func:`source_point_table`).

    Attributes
    ----------
    table : (9, P) float64
        Position (mm), unit normal, unit refracted direction of each point.
    weights : (C, P) float64
        Vertices: ``phi``; rule points: ``area * w_q * phi(x_q)``; midpoints: ``phi(x)`` (the rule's
        weight and the area are applied per receiver).
    vertex_lit : (n,) bool
        Whether light enters at the vertex.
    vertex_column : (n,) int32
        Column of each vertex of a lit triangle (the first ``held`` columns), -1 for the others.
    held : int
        Vertices in the table: the corners of its lit triangles.
    first_mid : int
        Column of the first edge midpoint (after the rule points).
    first_rule : (m,) int32
        Column of triangle ``t``'s first Dunavant point (its centroid, which the degree-3 rule uses
        too), or -1 where no light enters at any corner.
    midpoint_column : (e,) int32
        Column of each edge's midpoint (-1 where neither triangle of the edge has light).
    corners, lit_triangles, lit_edges, candidates : int64
        The vertices, the lit triangles and their edges that have columns, and the triangles looked at (the
        entries of the maps that :meth:`ColumnMaps.clear` puts back).
    """

    table: np.ndarray
    weights: np.ndarray
    vertex_lit: np.ndarray
    vertex_column: np.ndarray
    held: int
    first_mid: int
    first_rule: np.ndarray
    midpoint_column: np.ndarray
    corners: np.ndarray
    lit_triangles: np.ndarray
    lit_edges: np.ndarray
    candidates: np.ndarray


@dataclass
class TriangleTables:
    """Geometry-only triangle data of the near field (cached per mesh by the solver).

    Attributes
    ----------
    diameters : (m,) float64
        Longest edge of each triangle, mm.
    centroids : (m, 3) float64
        Centroid of each triangle, mm.
    n_edges : int
        Number of unique undirected edges.
    edge_of_corner : (m, 3) int32 (int64 from 2**31 edges)
        Edge from corner ``i`` to corner ``i + 1`` of each triangle.
    """

    diameters: np.ndarray
    centroids: np.ndarray
    n_edges: int
    edge_of_corner: np.ndarray


def triangle_tables(points, triangles) -> TriangleTables:
    """:class:`TriangleTables` of a mesh (``points`` in mm)."""
    edge_of_corner, n_edges = corner_edge_numbers(triangles)  # int32 where it fits: it spans the mesh
    return TriangleTables(
        longest_edges(points, triangles),
        triangle_centroids(points, triangles),
        n_edges,
        edge_of_corner,
    )


_KEPT = PerSurface("near field tables, grids and lists")


def tables_of(surface) -> TriangleTables:
    """:func:`triangle_tables` of ``surface`` (a :class:`~translucency.scatter.surface.SurfaceGeometry`), kept while
    it lives (geometry only)."""
    return _KEPT.get(surface, "tables", lambda: triangle_tables(surface.points, surface.triangles))


def vertices_near(points, centres, radius: float) -> np.ndarray:
    """Whether each of ``points (n, 3)`` is within ``radius`` (mm) of one of ``centres (k, 3)``, without a grid or a
    tree of the points: the centres are taken :data:`~translucency.scatter.treewalk.GROUP_RECEIVERS` at a time in
    their order (neighbours, as the solver's samples come), and a point is tested against a group's members only
    where it lies within the group's bounding sphere grown by ``radius``. For a few hundred centres on a scan (the
    budget's sample), one pass over the points."""
    near = np.zeros(len(points), dtype=np.bool_)
    if len(centres) == 0:
        return near
    centres = kernel_array(centres, np.float64)
    middle, spread, members = group_spheres(centres, GROUP_RECEIVERS)
    for_ranges(_points_near, near.size, kernel_array(points, np.float64), centres, middle, spread, members,
               float(radius), near)  # fmt: skip
    return near


@numba.njit(cache=True, nogil=True)
def _points_near(worker, lo, hi, points, centres, middle, spread, members, radius, near):
    """Points ``lo .. hi - 1`` of :func:`vertices_near`."""
    r2 = radius * radius
    for i in range(lo, hi):
        x0, x1, x2 = points[i, 0], points[i, 1], points[i, 2]
        for g in range(middle.shape[0]):
            reach = radius + spread[g]
            if (x0 - middle[g, 0]) ** 2 + (x1 - middle[g, 1]) ** 2 + (x2 - middle[g, 2]) ** 2 > reach * reach:
                continue
            for c in members[g]:
                if (x0 - centres[c, 0]) ** 2 + (x1 - centres[c, 1]) ** 2 + (x2 - centres[c, 2]) ** 2 <= r2:
                    near[i] = True
                    break
            if near[i]:
                break


def grid_of(surface, radius: float) -> NearGrid:
    """:func:`near_grid` of ``surface`` for ``radius`` (mm), kept per radius: blocks of receivers list their near
    triangles without rebuilding it."""
    return _KEPT.get(surface, ("grid", round(radius, 12)), lambda: near_grid(surface.points, surface.triangles, radius))


def lists_of(surface, receivers: np.ndarray, radius: float):
    """Near triangles of each receiver of ``surface`` within ``radius`` (mm; CSR ``(offsets, ids)``), kept per
    (receivers, radius)."""
    every = receivers.size >= surface.n_vertices
    key = ("lists", "all" if every else receivers.tobytes(), round(radius, 12))
    return _KEPT.get(surface, key, lambda: grid_of(surface, radius).lists(receivers))


@dataclass
class ColumnMaps:
    """Where each vertex, triangle and edge of the mesh has its columns in a block's :class:`SourcePoints`: arrays
    that span the mesh, made once per light (:func:`column_maps`) and reused by every block of receivers, which
    sets the entries of its own neighbourhood and puts them back (:meth:`clear`). Made afresh per block, they
    cost a pass over memory the size of the mesh for every block.

    Attributes
    ----------
    vertex_lit : (n,) bool
        Whether light enters at the vertex.
    vertex_column, first_rule, midpoint_column : (n,), (m,), (e,) int32
        As in :class:`SourcePoints`; -1 outside a block.
    listed : (m,) bool
        The triangles a block's receivers list; False outside a block.
    busy : bool
        A block's entries are set and not yet put back (a block given busy maps is refused: their stale entries
        would point into another block's table).
    """

    vertex_lit: np.ndarray
    vertex_column: np.ndarray
    first_rule: np.ndarray
    midpoint_column: np.ndarray
    listed: np.ndarray
    busy: bool = False

    def clear(self, shared: SourcePoints) -> None:
        """Put back the entries a block's ``shared`` points set (their cost is the block's, not the mesh's)."""
        self.vertex_column[shared.corners] = -1
        self.first_rule[shared.lit_triangles] = -1
        self.midpoint_column[shared.lit_edges] = -1
        self.listed[shared.candidates] = False
        self.busy = False


def column_maps(phi, n_triangles: int, n_edges: int) -> ColumnMaps:
    """Empty :class:`ColumnMaps` for the light ``phi (n, C)`` on a mesh of ``n_triangles`` triangles and
    ``n_edges`` edges (the columns as int32: a block's table holds far fewer than 2**31 columns, 96 bytes each)."""
    n = phi.shape[0]
    return ColumnMaps(
        phi.sum(axis=1) > 0,
        np.full(n, -1, dtype=np.int32),
        np.full(n_triangles, -1, dtype=np.int32),
        np.full(n_edges, -1, dtype=np.int32),
        np.zeros(n_triangles, dtype=bool),
    )


def source_point_table(
    points,
    normals,
    w12,
    phi,
    triangles,
    triangle_areas,
    tables: TriangleTables,
    rule_points=RULE_POINTS,
    rule_weights=RULE_WEIGHTS,
    within=None,
    maps: ColumnMaps | None = None,
) -> SourcePoints:
    """Quadrature points every receiver shares (made as :func:`gather_point` makes them).

    The columns are the corners of the triangles with light at a corner (``vertex_column`` maps a vertex to
    its own), then ``len(rule_points)`` Dunavant points per such triangle (the first is the centroid), then the
    midpoints of their edges. ``within`` (triangle ids), when given, limits the triangles to those: the ones
    some receivers list, so that a block of receivers holds the points of its neighbourhood only, not a column
    for every vertex of the mesh. ``maps`` (:func:`column_maps` of this light), when given, are filled for these
    points and must be cleared (:meth:`ColumnMaps.clear`) before the next block's; else fresh ones are made.
    """
    if maps is None:
        maps = column_maps(phi, triangles.shape[0], tables.n_edges)
    if maps.busy:
        raise RuntimeError("the near field's column maps still hold an earlier block's entries (not cleared).")
    maps.busy = True
    if within is None:
        candidates = np.arange(triangles.shape[0])
    else:
        candidates = _listed_once(within, maps.listed)
    vertex_column, first_rule, midpoint_column = maps.vertex_column, maps.first_rule, maps.midpoint_column
    n_rule = rule_points.shape[0]
    lit_triangles, corners, lit_edges, edge_triangles = _numbered_columns(
        triangles,
        candidates,
        maps.vertex_lit,
        tables.edge_of_corner,
        vertex_column,
        first_rule,
        midpoint_column,
        n_rule,
    )
    n = corners.size
    start_mid = n + n_rule * lit_triangles.size
    size = start_mid + lit_edges.size
    table = np.zeros((9, size))
    weights = np.zeros((phi.shape[1], size))
    table[0:3, :n] = points[corners].T
    table[3:6, :n] = normals[corners].T
    table[6:9, :n] = w12[corners].T
    weights[:, :n] = phi[corners].T
    for_ranges(
        _fill_shared_points,
        lit_triangles.size + edge_triangles.shape[0],
        points,
        normals,
        w12,
        phi,
        triangles,
        triangle_areas,
        rule_points,
        rule_weights,
        lit_triangles,
        edge_triangles,
        table,
        weights,
        n,
        start_mid,
    )
    return SourcePoints(
        table,
        weights,
        maps.vertex_lit,
        vertex_column,
        n,
        start_mid,
        first_rule,
        midpoint_column,
        corners,
        lit_triangles,
        lit_edges,
        candidates,
    )


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _listed_once(within, listed):
    """The triangles of ``within`` each once, in the order they are met, marked in ``listed`` (False on entry)."""
    once = np.empty(min(within.shape[0], listed.shape[0]), np.int64)
    n = 0
    for t in within:
        if not listed[t]:
            listed[t] = True
            once[n] = t
            n += 1
    return once[:n]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _numbered_columns(
    triangles, candidates, vertex_lit, edge_of_corner, vertex_column, first_rule, midpoint_column, n_rule
):
    """The columns of a block's shared points, set in the maps (whose entries are -1 on entry): each corner of a
    candidate triangle with light at a corner (``vertex_column``, in the order they are met), then ``n_rule`` rule
    points per such triangle (``first_rule``), then each of their edges' midpoint (``midpoint_column``). Returns the
    lit triangles, the corners, the edges, and each edge as a degenerate triangle ``(a, b, b)`` of its ends (smaller
    first, from the first lit triangle that has it), which interpolates as the edge does."""
    lit = np.empty(candidates.shape[0], np.int64)
    corners = np.empty(3 * candidates.shape[0], np.int64)
    n_lit = 0
    n = 0
    for t in candidates:
        if not (vertex_lit[triangles[t, 0]] or vertex_lit[triangles[t, 1]] or vertex_lit[triangles[t, 2]]):
            continue
        lit[n_lit] = t
        n_lit += 1
        for c in range(3):
            v = triangles[t, c]
            if vertex_column[v] < 0:
                vertex_column[v] = n
                corners[n] = v
                n += 1
    start_mid = n + n_rule * n_lit
    edges = np.empty(3 * n_lit, np.int64)
    ends = np.empty((3 * n_lit, 3), np.int64)
    m = 0
    for j in range(n_lit):
        t = lit[j]
        first_rule[t] = n + n_rule * j
        for c in range(3):
            e = edge_of_corner[t, c]
            if midpoint_column[e] < 0:
                midpoint_column[e] = start_mid + m
                edges[m] = e
                a, b = triangles[t, c], triangles[t, (c + 1) % 3]
                if b < a:
                    a, b = b, a
                ends[m, 0] = a
                ends[m, 1] = b
                ends[m, 2] = b
                m += 1
    return lit[:n_lit], corners[:n], edges[:m], ends[:m]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fill_shared_points(
    worker,
    lo,
    hi,
    points,
    normals,
    w12,
    phi,
    triangles,
    triangle_areas,
    rule_points,
    rule_weights,
    lit_triangles,
    edge_triangles,
    table,
    weights,
    start_rule,
    start_mid,
):
    """Dunavant points of the lit triangles and midpoints of their edges into ``table``: items ``lo .. hi - 1``
    of the lit triangles followed by the edges."""
    n_rule = rule_points.shape[0]
    n_lit = lit_triangles.shape[0]
    for k in range(lo, hi):
        if k < n_lit:
            t = lit_triangles[k]
            column = start_rule + k * n_rule
            for q in range(n_rule):
                gather_point(
                    points,
                    normals,
                    w12,
                    phi,
                    triangles[t],
                    rule_points[q, 0],
                    rule_points[q, 1],
                    rule_points[q, 2],
                    triangle_areas[t] * rule_weights[q],
                    table,
                    weights,
                    column + q,
                )
        else:
            gather_point(
                points,
                normals,
                w12,
                phi,
                edge_triangles[k - n_lit],
                0.5,
                0.25,
                0.25,
                1.0,
                table,
                weights,
                start_mid + k - n_lit,
            )


@numba.njit(cache=True, inline="always")
def integrated_whole(diameter, centroid, xo, beta, scale_min):
    """Whether a triangle is far enough from ``x_o`` to be integrated whole with the rule (the
    refinement test of :func:`subdivided_pieces` applied to the triangle itself)."""
    d2 = 0.0
    for i in range(3):
        d2 += (centroid[i] - xo[i]) ** 2
    return diameter <= beta * max(math.sqrt(d2), scale_min)


@numba.njit(cache=True, inline="always")
def by_degree3(diameter, centroid, xo, ratio, widest, scale_min):
    """Whether a whole triangle takes the degree-3 rule of shared points (:data:`CORNER_WEIGHT`, ...) at ``x_o``:
    no wider than ``widest`` (mm), at least ``1 / ratio`` of its ``diameter`` away (``ratio`` 0: never), and only
    beyond ``scale_min`` (mm; ``D_min``): nearer, ``S_d`` varies with the angles too."""
    return (
        diameter <= widest
        and integrated_whole(diameter, centroid, xo, ratio, 0.0)
        and integrated_whole(scale_min, centroid, xo, 1.0, 0.0)
    )


@numba.njit(cache=True, fastmath=True)
def subdivided_pieces(points, tri, xo, beta, scale_min, stack, cx, out):
    """Adaptive midpoint subdivision of a triangle that is too close to be integrated whole.

    A piece is accepted when its diameter is at most ``beta * max(distance to x_o, scale_min)`` (or at
    depth :data:`MAX_DEPTH`). Writes the accepted pieces to ``out`` (rows: barycentric ``(b0, b1)`` of
    the three corners, then depth) when ``out`` has room, and returns how many there are.
    """
    a, b, c = tri[0], tri[1], tri[2]
    top = 0
    for child in (
        (1.0, 0.0, 0.5, 0.5, 0.5, 0.0),
        (0.5, 0.5, 0.0, 1.0, 0.0, 0.5),
        (0.5, 0.0, 0.0, 0.5, 0.0, 0.0),
        (0.5, 0.5, 0.0, 0.5, 0.5, 0.0),
    ):  # the four children of the whole triangle
        for i in range(6):
            stack[top, i] = child[i]
        stack[top, 6] = 1.0
        top += 1
    n = 0
    while top > 0:
        top -= 1
        p0, q0, p1, q1, p2, q2, depth = (
            stack[top, 0],
            stack[top, 1],
            stack[top, 2],
            stack[top, 3],
            stack[top, 4],
            stack[top, 5],
            stack[top, 6],
        )
        r0 = 1.0 - p0 - q0
        r1 = 1.0 - p1 - q1
        r2 = 1.0 - p2 - q2
        for i in range(3):
            cx[0, i] = p0 * points[a, i] + q0 * points[b, i] + r0 * points[c, i]
            cx[1, i] = p1 * points[a, i] + q1 * points[b, i] + r1 * points[c, i]
            cx[2, i] = p2 * points[a, i] + q2 * points[b, i] + r2 * points[c, i]
        h2 = 0.0
        for u, v in ((0, 1), (1, 2), (2, 0)):
            e = (cx[u, 0] - cx[v, 0]) ** 2 + (cx[u, 1] - cx[v, 1]) ** 2 + (cx[u, 2] - cx[v, 2]) ** 2
            if e > h2:
                h2 = e
        dist2 = 0.0
        for i in range(3):
            dist2 += ((cx[0, i] + cx[1, i] + cx[2, i]) / 3.0 - xo[i]) ** 2
        if math.sqrt(h2) <= beta * max(math.sqrt(dist2), scale_min) or depth >= MAX_DEPTH:
            if n < out.shape[0]:
                out[n, 0] = p0
                out[n, 1] = q0
                out[n, 2] = p1
                out[n, 3] = q1
                out[n, 4] = p2
                out[n, 5] = q2
                out[n, 6] = depth
            n += 1
        else:
            m01p = 0.5 * (p0 + p1)
            m01q = 0.5 * (q0 + q1)
            m12p = 0.5 * (p1 + p2)
            m12q = 0.5 * (q1 + q2)
            m20p = 0.5 * (p2 + p0)
            m20q = 0.5 * (q2 + q0)
            children = (
                (p0, q0, m01p, m01q, m20p, m20q),
                (m01p, m01q, p1, q1, m12p, m12q),
                (m20p, m20q, m12p, m12q, p2, q2),
                (m01p, m01q, m12p, m12q, m20p, m20q),
            )
            for child in children:
                for i in range(6):
                    stack[top, i] = child[i]
                stack[top, 6] = depth + 1.0
                top += 1
    return n


#: Widest angle (rad) one set of the fan's angular nodes covers; wider corners are split into sectors.
FAN_SECTOR = math.pi / 3
#: Longest stretch of ``u = log(1 + r / c)`` one set of radial nodes covers (``L / c`` up to ~20 in one).
FAN_SPAN = 3.0


@numba.njit(cache=True)
def corner_frame(points, tri, corner, scale):
    """The triangle seen from its corner ``corner``: first edge length ``a``, second edge in the frame
    (``bu`` along the first edge, ``bv`` across), twice the area, the corner's angle (rad), the number
    of fan sectors (``ceil(angle / FAN_SECTOR)``; 0 for a degenerate triangle) and of radial stretches
    (``ceil(log(1 + longest edge / scale) / FAN_SPAN)``).

    Compiled once, without ``fastmath`` and not inlined: :func:`fan_count` (which sizes the buffers)
    and :func:`fan_rule` (which fills them, with ``fastmath``) must get the same counts to the bit."""
    i0 = tri[corner]
    i1 = tri[(corner + 1) % 3]
    i2 = tri[(corner + 2) % 3]
    e10 = points[i1, 0] - points[i0, 0]
    e11 = points[i1, 1] - points[i0, 1]
    e12 = points[i1, 2] - points[i0, 2]
    e20 = points[i2, 0] - points[i0, 0]
    e21 = points[i2, 1] - points[i0, 1]
    e22 = points[i2, 2] - points[i0, 2]
    a = math.sqrt(e10 * e10 + e11 * e11 + e12 * e12)
    c0 = e11 * e22 - e12 * e21
    c1 = e12 * e20 - e10 * e22
    c2 = e10 * e21 - e11 * e20
    area2 = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    if not (a > 0.0 and area2 > 1e-12 * a * a):
        return a, 0.0, 0.0, area2, 0.0, 0, 0
    bu = (e10 * e20 + e11 * e21 + e12 * e22) / a
    bv = area2 / a
    alpha = math.atan2(bv, bu)
    longest = max(a, math.sqrt(e20 * e20 + e21 * e21 + e22 * e22))  # the farthest point is a corner
    stretches = max(1, int(math.ceil(math.log1p(longest / scale) / FAN_SPAN)))
    return a, bu, bv, area2, alpha, max(1, int(math.ceil(alpha / FAN_SECTOR))), stretches


@numba.njit(cache=True)
def fan_count(points, tri, corner, scale, n_ang, n_rad):
    """Number of points :func:`fan_rule` writes for this triangle, corner and radial scale ``c`` (mm)."""
    frame = corner_frame(points, tri, corner, scale)
    return frame[5] * frame[6] * n_ang * n_rad


@numba.njit(cache=True, inline="always")
def fan_ray(a, bu, bv, alpha, share, scale, stretches):
    """The fan's ray at the angle ``share * alpha`` from the first edge of a :func:`corner_frame` (``a, bu, bv``
    mm, ``alpha`` rad): where it meets the opposite edge (``t``, from its first end), its length (mm) and the step
    of ``u = log(1 + r / scale)`` a radial stretch covers."""
    theta = alpha * share
    sin_t = math.sin(theta)
    cos_t = math.cos(theta)
    t = a * sin_t / (bv * cos_t + (a - bu) * sin_t)
    length = math.sqrt(((1.0 - t) * a + t * bu) ** 2 + (t * bv) ** 2)
    return t, length, math.log1p(length / scale) / stretches


@numba.njit(cache=True, fastmath=True)
def fan_rule(points, tri, corner, beta, scale_min, ang_x, ang_w, rad_x, rad_w, out):
    """Polar ("fan") rule over a triangle around its corner ``corner``, where the receiver sits.

    In polar coordinates about the corner, ``dA = r dr dtheta``: the integral is
    ``int_0^alpha dtheta int_0^L(theta) f r dr`` (``alpha`` the corner's angle, ``L`` the distance to the
    opposite edge along the ray). Gauss-Legendre in ``theta`` (``ang_x, ang_w`` on [0, 1], per sector of
    at most :data:`FAN_SECTOR`; the polar angle, not a parameter along the opposite edge, keeps the
    integrand smooth even at obtuse corners) and, along every ray, in ``u = log(1 + r / c)`` on
    ``[0, log(1 + L / c)]`` with ``c = beta * scale_min`` and ``dr = (r + c) du``: the peak of width
    ``D`` at the receiver and the ``1/r^3`` tail beyond it both become smooth in ``u`` (split into
    stretches of at most :data:`FAN_SPAN` on triangles much larger than ``c``). So few nodes, 3 x 5 per
    sector, give the adaptive subdivision's answer with far fewer points (tests/scatter/test_nearfield.py
    checks it against an adaptive integral; bench/README.md, "Kernel throughput").

    Writes :func:`fan_count` rows ``(b_0, b_1, b_2, weight / area)`` in the triangle's corner order to
    ``out`` (none for a degenerate triangle).
    """
    scale = beta * scale_min  # c
    a, bu, bv, area2, alpha, sectors, stretches = corner_frame(points, tri, corner, scale)
    n = 0
    for sector in range(sectors):
        for j in range(ang_x.shape[0]):
            t, length, du = fan_ray(a, bu, bv, alpha, (sector + ang_x[j]) / sectors, scale, stretches)
            for stretch in range(stretches):
                for k in range(rad_x.shape[0]):
                    r = scale * math.expm1(du * (stretch + rad_x[k]))
                    s = r / length
                    out[n, corner] = 1.0 - s
                    out[n, (corner + 1) % 3] = s * (1.0 - t)
                    out[n, (corner + 2) % 3] = s * t
                    out[n, 3] = alpha / sectors * ang_w[j] * du * rad_w[k] * (r + scale) * r * 2.0 / area2
                    n += 1


@numba.njit(cache=True, fastmath=True)
def fan_gathered(points, normals, w12, phi, tri, corner, area, beta, scale_min, fan, buf, weights, column):
    """:func:`fan_rule` about ``corner`` of ``tri`` (area mm^2; ``fan`` its nodes ``(ang_x, ang_w, rad_x, rad_w)``)
    with each point gathered as :func:`gather_point` gathers it, into columns ``column ..`` of ``buf`` and
    ``weights``; returns the next column.

    Along a ray from the corner to the opposite edge the barycentric coordinates are ``(1 - s, s (1 - t), s t)``,
    so every quantity :func:`gather_point` interpolates is ``q_corner + s (q_end - q_corner)``, ``q_end`` the
    ray's end on the edge: each point costs one multiply-add per quantity instead of a sum over three corners.
    """
    ang_x, ang_w, rad_x, rad_w = fan
    scale = beta * scale_min
    a, bu, bv, area2, alpha, sectors, stretches = corner_frame(points, tri, corner, scale)
    i0, i1, i2 = tri[corner], tri[(corner + 1) % 3], tri[(corner + 2) % 3]
    n_out = phi.shape[1]
    f0, f1, f2 = corner_flux(phi, i0, i1, i2)
    first = tri[0]  # where no light enters, the point is a copy of the first corner (as gather_point's)
    p00, p01, p02 = points[i0, 0], points[i0, 1], points[i0, 2]
    n00, n01, n02 = normals[i0, 0], normals[i0, 1], normals[i0, 2]
    v00, v01, v02 = f0 * w12[i0, 0], f0 * w12[i0, 1], f0 * w12[i0, 2]
    for sector in range(sectors):
        for j in range(ang_x.shape[0]):
            t, length, du = fan_ray(a, bu, bv, alpha, (sector + ang_x[j]) / sectors, scale, stretches)
            u = 1.0 - t
            # the ray's end on the opposite edge, less the corner: what a step in s adds
            df = u * f1 + t * f2 - f0
            dp0 = u * points[i1, 0] + t * points[i2, 0] - points[i0, 0]
            dp1 = u * points[i1, 1] + t * points[i2, 1] - points[i0, 1]
            dp2 = u * points[i1, 2] + t * points[i2, 2] - points[i0, 2]
            dn0 = u * normals[i1, 0] + t * normals[i2, 0] - normals[i0, 0]
            dn1 = u * normals[i1, 1] + t * normals[i2, 1] - normals[i0, 1]
            dn2 = u * normals[i1, 2] + t * normals[i2, 2] - normals[i0, 2]
            dv0 = u * f1 * w12[i1, 0] + t * f2 * w12[i2, 0] - f0 * w12[i0, 0]
            dv1 = u * f1 * w12[i1, 1] + t * f2 * w12[i2, 1] - f0 * w12[i0, 1]
            dv2 = u * f1 * w12[i1, 2] + t * f2 * w12[i2, 2] - f0 * w12[i0, 2]
            for stretch in range(stretches):
                for k in range(rad_x.shape[0]):
                    r = scale * math.expm1(du * (stretch + rad_x[k]))
                    s = r / length
                    weight = alpha / sectors * ang_w[j] * du * rad_w[k] * (r + scale) * r * 2.0 / area2 * area
                    m0 = n00 + s * dn0
                    m1 = n01 + s * dn1
                    m2 = n02 + s * dn2
                    mn = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
                    if mn <= 0.0:
                        m0, m1, m2, mn = 0.0, 0.0, 1.0, 1.0
                    v0 = v00 + s * dv0
                    v1 = v01 + s * dv1
                    v2 = v02 + s * dv2
                    vn = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
                    buf[3, column] = m0 / mn
                    buf[4, column] = m1 / mn
                    buf[5, column] = m2 / mn
                    if f0 + s * df <= 0.0 or vn <= 0.0:  # no light enters here
                        buf[0, column] = points[first, 0]
                        buf[1, column] = points[first, 1]
                        buf[2, column] = points[first, 2]
                        buf[6, column] = -m0 / mn
                        buf[7, column] = -m1 / mn
                        buf[8, column] = -m2 / mn
                        for ch in range(n_out):
                            weights[ch, column] = 0.0
                    else:
                        buf[0, column] = p00 + s * dp0
                        buf[1, column] = p01 + s * dp1
                        buf[2, column] = p02 + s * dp2
                        buf[6, column] = v0 / vn
                        buf[7, column] = v1 / vn
                        buf[8, column] = v2 / vn
                        for ch in range(n_out):
                            weights[ch, column] = weight * (
                                phi[i0, ch] + s * (u * phi[i1, ch] + t * phi[i2, ch] - phi[i0, ch])
                            )
                    column += 1
    return column


@numba.njit(cache=True, inline="always")
def corner_of(tri, vertex):
    """Which corner of ``tri`` is ``vertex`` (0, 1, 2), or -1."""
    for corner in range(3):
        if tri[corner] == vertex:
            return corner
    return -1


def near_field_correction(
    model,
    points,
    triangles,
    triangle_areas,
    normals,
    w12,
    phi,
    receivers,
    offsets,
    triangle_ids,
    params,
    channel_of,
    beta,
    scale_min,
    tables=None,
    degree3_ratio=0.0,
    degree3_diameter=math.inf,
    rule_points=RULE_POINTS,
    rule_weights=RULE_WEIGHTS,
    fan_nodes=(FAN_ANGULAR, FAN_RADIAL),
    refined_out=None,
    maps: ColumnMaps | None = None,
):
    """Correction ``C[r, c]`` of the vertex sum for every receiver ``r`` (see the module docstring).

    Receivers are done in blocks of :data:`BLOCK_RECEIVERS`: (1) list each receiver's quadrature
    points -- the vertex rule of its near triangles (each vertex once, weighted by the sum of the near
    triangles' thirds), the shared rule points of the triangles far enough to be integrated whole, and a
    count of its own points: the fan rule (:func:`fan_rule`) on the triangles around it and the refined
    pieces of the other close ones; (2) make its own points; (3) evaluate every receiver's points with
    :func:`~translucency.scatter.kernels.indexed_sum` (where the time goes).

    Whole triangles use Dunavant's degree-5 rule, or the cheaper degree-3 rule (shared midpoints and
    centroids) where ``diameter <= degree3_ratio * distance``, ``distance >= scale_min`` and ``diameter <=
    degree3_diameter`` (mm; ``degree3_ratio`` 0: never; nearer than ``D_min``, ``S_d`` varies with the angles
    too, and over a triangle wider than a fraction of ``1 / sigma_tr`` faster than the rule follows).
    ``tables`` are the mesh's
    :class:`TriangleTables` (made here when not given). The shared points (:func:`source_point_table`) are
    made here for the triangles these receivers list only, so that a call holds its neighbourhood's; ``maps``
    (:func:`column_maps` of this light), when given, are used for them and left as they were on return.
    ``refined_out`` (n_receivers,) int64, when given, receives the number of each receiver's own points.

    Returns
    -------
    correction : (n_receivers, C) float64
    points : (n_receivers,) int64
        Number of quadrature points evaluated per receiver (vertex rule included).
    """
    if tables is None:
        tables = triangle_tables(points, triangles)
    degree3_ratio = min(degree3_ratio, beta)  # a degree-3 triangle is one the refinement leaves whole
    if not np.allclose(rule_points[0], 1.0 / 3.0):
        raise ValueError("the rule's first point must be the centroid (the degree-3 rule shares it)")
    centroid_factor = CENTROID_WEIGHT / float(rule_weights[0])  # its weight is area * w_0 * phi
    shared = source_point_table(
        points,
        normals,
        w12,
        phi,
        triangles,
        triangle_areas,
        tables,
        rule_points,
        rule_weights,
        within=triangle_ids[offsets[0] : offsets[-1]],
        maps=maps,
    )
    diameters, centroids = tables.diameters, tables.centroids
    lanes = channel_lanes(params, channel_of, phi.shape[1])
    fan = (*gauss_legendre_unit(fan_nodes[0]), *gauss_legendre_unit(fan_nodes[1]))
    n_r = receivers.shape[0]
    n_c = phi.shape[1]
    correction = np.zeros((n_r, n_c))
    n_points = np.zeros(n_r, dtype=np.int64)
    bound = np.zeros(n_r + 1, dtype=np.int64)  # room for each receiver's listed columns
    np.cumsum((3 + rule_points.shape[0]) * np.diff(offsets), out=bound[1:])
    starts = range(0, n_r, BLOCK_RECEIVERS)
    room = max((bound[min(n_r, s + BLOCK_RECEIVERS)] - bound[s] for s in starts), default=0)
    columns = np.empty(room, dtype=np.int64)  # buffers reused by every block (no fresh pages per block)
    factors = np.empty(room)
    # the positions of the triangles that take a receiver's own points, in its list of near triangles
    own_items = np.empty(
        max((offsets[min(n_r, s + BLOCK_RECEIVERS)] - offsets[s] for s in starts), default=0), np.int64
    )
    own = np.empty(0)
    ones = np.empty(0)
    # receiver numbers and list slots of the table's vertices and midpoints (int32: half the memory)
    n_mid = shared.table.shape[1] - shared.first_mid
    stamps = np.full((thread_count(), 2 * (shared.held + n_mid)), -1, dtype=np.int32)
    for start in starts:
        block = slice(start, min(n_r, start + BLOCK_RECEIVERS))
        rcv = receivers[block]
        col_offsets = bound[start : block.stop + 1] - bound[start]
        n_columns = np.zeros(rcv.size, dtype=np.int64)
        n_refined = np.zeros(rcv.size, dtype=np.int64)
        n_own = np.zeros(rcv.size, dtype=np.int64)
        for_ranges(
            _list_points,
            rcv.size,
            points,
            triangles,
            triangle_areas,
            rcv,
            offsets[start : block.stop + 1],
            triangle_ids,
            beta,
            scale_min,
            degree3_ratio,
            degree3_diameter,
            centroid_factor,
            shared.vertex_lit,
            shared.vertex_column,
            shared.held,
            shared.first_rule,
            shared.midpoint_column,
            shared.first_mid,
            tables.edge_of_corner,
            diameters,
            centroids,
            fan[0].size,
            fan[2].size,
            col_offsets,
            columns,
            factors,
            n_columns,
            n_refined,
            own_items,
            n_own,
            start,
            stamps,
        )
        n_points[block] = n_columns + n_refined
        if refined_out is not None:
            refined_out[block] = n_refined
        ref_offsets = np.zeros(rcv.size + 1, dtype=np.int64)
        np.cumsum(n_refined, out=ref_offsets[1:])
        size = int(ref_offsets[-1])
        if own.size < (9 + n_c) * size:
            own = np.empty(int(1.25 * (9 + n_c) * size))
            ones = np.ones(own.size // (9 + n_c))
        refined = own[: 9 * size].reshape(9, size)  # every column is written
        refined_weights = own[9 * size : (9 + n_c) * size].reshape(n_c, size)
        for_ranges(
            _refined_points,
            rcv.size,
            points,
            normals,
            w12,
            phi,
            triangles,
            triangle_areas,
            rcv,
            offsets[start : block.stop + 1],
            triangle_ids,
            beta,
            scale_min,
            own_items,
            n_own,
            rule_points,
            rule_weights,
            fan,
            ref_offsets,
            refined,
            refined_weights,
        )
        rcv_points, rcv_normals = points[rcv], normals[rcv]
        correction[block] = indexed_sum(
            model,
            rcv_points,
            rcv_normals,
            shared.table,
            shared.weights,
            col_offsets[:-1],
            n_columns,
            columns,
            factors,
            lanes,
        ) + indexed_sum(
            model,
            rcv_points,
            rcv_normals,
            refined,
            refined_weights,
            ref_offsets[:-1],
            np.diff(ref_offsets),
            np.arange(size),
            ones[:size],
            lanes,
        )
    if maps is not None:  # the next block's (after an error, the solve and its maps are given up)
        maps.clear(shared)
    return correction, n_points


#: Receivers whose quadrature points are listed at a time (bounds the memory of the listing, which grows with
#: the receivers of a block times their near triangles).
BLOCK_RECEIVERS = 2048


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _list_points(
    worker,
    lo,
    hi,
    points,
    triangles,
    triangle_areas,
    receivers,
    offsets,
    triangle_ids,
    beta,
    scale_min,
    degree3_ratio,
    degree3_diameter,
    centroid_factor,
    vertex_lit,
    vertex_column,
    held,
    first_rule,
    midpoint_column,
    first_mid,
    edge_of_corner,
    diameters,
    centroids,
    fan_angular,
    fan_radial,
    col_offsets,
    columns,
    factors,
    n_columns,
    n_refined,
    own_items,
    n_own,
    first_receiver,
    stamps,
):
    """Pass 1: per receiver, the shared-table points (vertex rule, whole triangles) and the number of
    points of its own quadrature (fan rule on its own triangles, refined pieces of the other close ones), with
    the positions in ``triangle_ids`` of the triangles that take them (``own_items``, from the receiver's first
    position in the block's lists on; ``n_own`` per receiver), so that pass 2 visits those alone.

    ``stamps`` (threads x (2 held + 2 midpoints), -1 at first, kept across blocks) holds, per thread, which
    receiver (``first_receiver + r``) last listed a vertex or an edge midpoint of the table (by its column:
    ``vertex_column[v]``, ``midpoint_column[e] - first_mid``) and where: allocating them per block instead would
    cost a pass over memory proportional to the table for every chunk of receivers.
    """
    n_v = held
    n_rule = RULE_POINTS.shape[0]
    # receivers lo .. hi - 1, with the scratch space and stamps of ``worker``
    stack = np.empty((3 * MAX_DEPTH + 8, 7))
    cx = np.empty((3, 3))
    none = np.empty((0, 7))
    mine = stamps[worker]
    n_e = mine.shape[0] // 2 - n_v
    owner = mine[:n_v]  # receiver that last listed a vertex
    slot = mine[n_v : 2 * n_v]  # its position in that receiver's list
    edge_owner = mine[2 * n_v : 2 * n_v + n_e]  # the same for edge midpoints
    edge_slot = mine[2 * n_v + n_e :]
    for r in range(lo, hi):
        me = first_receiver + r
        xo = points[receivers[r]]
        base = col_offsets[r]
        listed, refined, items = 0, 0, 0  # columns, own points, triangles with own points
        item_base = offsets[r] - offsets[0]
        for k in range(offsets[r], offsets[r + 1]):
            t = triangle_ids[k]
            if first_rule[t] < 0:  # no light enters at any corner: nothing to integrate
                continue
            third = triangle_areas[t] / 3.0
            for corner in range(3):
                v = triangles[t, corner]
                if not vertex_lit[v]:
                    continue
                cv = vertex_column[v]
                if owner[cv] != me:
                    owner[cv] = me
                    slot[cv] = listed
                    columns[base + listed] = cv
                    factors[base + listed] = 0.0
                    listed += 1
                factors[base + slot[cv]] -= third
            corner = corner_of(triangles[t], receivers[r])
            if corner >= 0:  # the receiver's own triangle: the fan rule
                refined += fan_count(points, triangles[t], corner, beta * scale_min, fan_angular, fan_radial)
                own_items[item_base + items] = k
                items += 1
            elif by_degree3(diameters[t], centroids[t], xo, degree3_ratio, degree3_diameter, scale_min):
                area = triangle_areas[t]
                for corner in range(3):
                    v = triangles[t, corner]
                    if vertex_lit[v]:
                        factors[base + slot[vertex_column[v]]] += CORNER_WEIGHT * area
                    column = midpoint_column[edge_of_corner[t, corner]]
                    e = column - first_mid
                    if edge_owner[e] != me:
                        edge_owner[e] = me
                        edge_slot[e] = listed
                        columns[base + listed] = column
                        factors[base + listed] = 0.0
                        listed += 1
                    factors[base + edge_slot[e]] += MIDPOINT_WEIGHT * area
                columns[base + listed] = first_rule[t]  # Dunavant's first point: the centroid
                factors[base + listed] = centroid_factor
                listed += 1
            elif integrated_whole(diameters[t], centroids[t], xo, beta, scale_min):  # Dunavant: shared rule points
                for q in range(n_rule):
                    columns[base + listed] = first_rule[t] + q
                    factors[base + listed] = 1.0
                    listed += 1
            else:
                refined += n_rule * subdivided_pieces(points, triangles[t], xo, beta, scale_min, stack, cx, none)
                own_items[item_base + items] = k
                items += 1
        n_columns[r] = listed
        n_refined[r] = refined
        n_own[r] = items


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _refined_points(
    worker,
    lo,
    hi,
    points,
    normals,
    w12,
    phi,
    triangles,
    triangle_areas,
    receivers,
    offsets,
    triangle_ids,
    beta,
    scale_min,
    own_items,
    n_own,
    rule_points,
    rule_weights,
    fan,
    ref_offsets,
    refined,
    refined_weights,
):
    """Pass 2: each receiver's own quadrature points (fan rule, refined pieces), from ``ref_offsets`` on, on the
    triangles pass 1 found (``own_items``, ``n_own``: :func:`_list_points`)."""
    # receivers lo .. hi - 1, with their own scratch space
    ang_x, ang_w, rad_x, rad_w = fan
    stack = np.empty((3 * MAX_DEPTH + 8, 7))
    cx = np.empty((3, 3))
    found = np.empty((4**6, 7))
    own = np.empty((4 * ang_x.shape[0] * rad_x.shape[0], 4))
    for r in range(lo, hi):
        xo = points[receivers[r]]
        column = ref_offsets[r]
        item_base = offsets[r] - offsets[0]
        for item in range(n_own[r]):
            t = triangle_ids[own_items[item_base + item]]
            tri = triangles[t]
            corner = corner_of(tri, receivers[r])
            if corner >= 0:  # the fan rule, gathered a ray at a time
                column = fan_gathered(
                    points,
                    normals,
                    w12,
                    phi,
                    tri,
                    corner,
                    triangle_areas[t],
                    beta,
                    scale_min,
                    fan,
                    refined,
                    refined_weights,
                    column,
                )
                continue
            n, own, found = _own_points(
                points,
                tri,
                triangle_areas[t],
                corner,
                xo,
                beta,
                scale_min,
                rule_points,
                rule_weights,
                ang_x,
                ang_w,
                rad_x,
                rad_w,
                stack,
                cx,
                found,
                own,
            )
            for j in range(n):
                gather_point(
                    points,
                    normals,
                    w12,
                    phi,
                    tri,
                    own[j, 0],
                    own[j, 1],
                    own[j, 2],
                    own[j, 3],
                    refined,
                    refined_weights,
                    column,
                )
                column += 1


@numba.njit(cache=True)
def _own_points(
    points,
    tri,
    area,
    corner,
    xo,
    beta,
    scale_min,
    rule_points,
    rule_weights,
    ang_x,
    ang_w,
    rad_x,
    rad_w,
    stack,
    cx,
    found,
    out,
):
    """A receiver's own quadrature points on the triangle ``tri`` (area mm^2): the fan rule about its corner
    ``corner`` (>= 0: the receiver's own triangle), else Dunavant's rule on the pieces of the subdivision.
    Rows ``(b0, b1, b2, weight mm^2)`` of ``out``; returns ``(count, out, found)`` (the scratch arrays, grown
    where they were too small)."""
    if corner >= 0:
        n = fan_count(points, tri, corner, beta * scale_min, ang_x.shape[0], rad_x.shape[0])
        if n > out.shape[0]:
            out = np.empty((n, 4))
        fan_rule(points, tri, corner, beta, scale_min, ang_x, ang_w, rad_x, rad_w, out)
        for j in range(n):
            out[j, 3] *= area
        return n, out, found
    n = subdivided_pieces(points, tri, xo, beta, scale_min, stack, cx, found)
    if n > found.shape[0]:  # deeper than the scratch space: grow it and subdivide again
        found = np.empty((n, 7))
        n = subdivided_pieces(points, tri, xo, beta, scale_min, stack, cx, found)
    n_rule = rule_points.shape[0]
    if n * n_rule > out.shape[0]:
        out = np.empty((n * n_rule, 4))
    m = 0
    for j in range(n):
        corners = (found[j, 0], found[j, 1], found[j, 2], found[j, 3], found[j, 4], found[j, 5])
        piece_area = area * 0.25 ** found[j, 6]
        for qp in range(n_rule):
            out[m, 0], out[m, 1], out[m, 2] = piece_point(
                corners, rule_points[qp, 0], rule_points[qp, 1], rule_points[qp, 2]
            )
            out[m, 3] = piece_area * rule_weights[qp]
            m += 1
    return m, out, found


@numba.njit(cache=True, inline="always")
def piece_point(corners, l0, l1, l2):
    """The barycentric coordinates in its triangle of the point ``(l0, l1, l2)`` of a piece of
    :func:`subdivided_pieces`, whose ``corners`` are ``(p0, q0, p1, q1, p2, q2)`` (corner ``k`` at ``(p_k, q_k, 1 -
    p_k - q_k)``)."""
    p0, q0, p1, q1, p2, q2 = corners
    r0 = 1.0 - p0 - q0
    r1 = 1.0 - p1 - q1
    r2 = 1.0 - p2 - q2
    return l0 * p0 + l1 * p1 + l2 * p2, l0 * q0 + l1 * q1 + l2 * q2, l0 * r0 + l1 * r1 + l2 * r2


def near_field_operator(
    model,
    points,
    triangles,
    triangle_areas,
    normals,
    vertex_areas,
    receivers,
    offsets,
    triangle_ids,
    params,
    beta,
    scale_min,
    fit,
    tables=None,
    rule_points=RULE_POINTS,
    rule_weights=RULE_WEIGHTS,
    fan_nodes=(FAN_ANGULAR, FAN_RADIAL),
    progress=None,
    degree3_ratio=0.0,
    degree3_diameter=math.inf,
):
    """The correction of :func:`near_field_correction` as a linear operator on the vertices' flux, for relighting.

    The same quadrature (fan rule on the receiver's own triangles, subdivided pieces of the close ones,
    Dunavant's rule on the others, the degree-3 rule where ``degree3_ratio`` and ``degree3_diameter`` allow it, as
    there: its corners join the vertices' own points and each edge's midpoint is one point for both its triangles)
    with every vertex treated as lit, ``Phi``,
    ``Psi = Phi w12`` and ``Xi = Phi w12 w12^T`` interpolated linearly, and ``S_d`` as the quadratic fit
    (docs/physics.md §8.7), the points of a receiver fitted :data:`POINT_BATCH` at a time by
    :func:`~translucency.scatter.fits.fitted_points`. The coefficient of a point is
    shared among the triangle's corners by their barycentric weights and divided by the corner's vertex
    area (per unit flux ``Phi = phi A``). Each near vertex's own pair of the vertex sum is included, with the
    quadratic fit, so that its row is the whole of what the vertex gives the receiver (the vertex rule of the
    near triangles and the vertex's own pair cancel where all its triangles are near; held apart, as the far
    field's and near field's separately rounded terms, they left coarse meshes tens of % off).

    Parameters
    ----------
    params : (C, N_PARAMS) float64
        Kernel parameters of every output channel.
    fit : tuple
        ``(dirs, pinv)`` of :func:`~translucency.scatter.fits.fit_directions` for the quadratic fit.
    vertex_areas : (n,) float64
        Barycentric vertex areas, mm^2 (a vertex of area 0 gets no coefficient).
    progress : callable, optional
        ``progress(fraction)`` as receivers are done (:func:`~translucency.threads.for_ranges`; if it raises,
        the work stops there).

    Returns
    -------
    starts : (n_receivers + 1,) int64
    columns : (E,) int64
        Receiver ``r``'s vertices are ``columns[starts[r]:starts[r + 1]]``.
    coefs : (E, 10 C) float32
        Per entry and channel the ten coefficients of the quadratic fit (1/(mm^2 sr) per unit flux).
    """
    if tables is None:
        tables = triangle_tables(points, triangles)
    degree3_ratio = min(degree3_ratio, beta)  # a degree-3 triangle is one the refinement leaves whole
    n_r = receivers.shape[0]
    counts = near_vertex_counts(triangles, receivers, offsets, triangle_ids)
    stamps = np.full((thread_count(), 2 * points.shape[0]), -1, dtype=np.int64)
    n_edges = tables.n_edges if degree3_ratio > 0.0 else 0
    edge_stamps = np.full((thread_count(), 2 * n_edges), -1, dtype=np.int64)  # per edge: receiver, slot
    fan = (*gauss_legendre_unit(fan_nodes[0]), *gauss_legendre_unit(fan_nodes[1]))
    starts = np.zeros(n_r + 1, dtype=np.int64)
    np.cumsum(counts, out=starts[1:])
    columns = np.empty(int(starts[-1]), dtype=np.int64)
    coefs = np.zeros((int(starts[-1]), QUADRATIC_TERMS * params.shape[0]), dtype=np.float32)
    for_ranges(
        _operator_rows,
        n_r,
        model,
        points,
        triangles,
        triangle_areas,
        normals,
        vertex_areas,
        receivers,
        offsets,
        triangle_ids,
        params,
        beta,
        scale_min,
        tables.diameters,
        tables.centroids,
        (float(degree3_ratio), float(degree3_diameter), tables.edge_of_corner, edge_stamps),
        rule_points,
        rule_weights,
        *fan,
        *fit,
        stamps,
        starts,
        columns,
        coefs,
        progress=progress,
    )
    return starts, columns, coefs


def near_vertex_counts(triangles, receivers, offsets, triangle_ids) -> np.ndarray:
    """Vertices of each receiver's near triangles (their distinct corners): the rows
    :func:`near_field_operator` makes per receiver."""
    counts = np.zeros(receivers.shape[0], dtype=np.int64)
    stamps = np.full((thread_count(), int(triangles.max(initial=0)) + 1), -1, dtype=np.int64)
    for_ranges(_operator_counts, receivers.shape[0], triangles, receivers, offsets, triangle_ids, stamps, counts)
    return counts


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _operator_counts(worker, lo, hi, triangles, receivers, offsets, triangle_ids, stamps, counts):
    """Distinct corners of each receiver's near triangles (receivers ``lo .. hi - 1``)."""
    owner = stamps[worker]
    for r in range(lo, hi):
        listed = 0
        for k in range(offsets[r], offsets[r + 1]):
            for corner in range(3):
                v = triangles[triangle_ids[k], corner]
                if owner[v] != r:
                    owner[v] = r
                    listed += 1
        counts[r] = listed


#: Quadrature points of a receiver's operator row fitted together (:func:`~translucency.scatter.fits.fitted_points`).
POINT_BATCH = 256


@numba.njit(cache=True, inline="always", fastmath=True)
def _queue_point(points, normals, tri, b0, b1, b2, weight, xo, no, batch, queued):
    """Queue the point with barycentric ``b`` of ``tri``, weight ``weight`` (mm^2), for the receiver at ``xo``
    with normal ``no`` in place ``queued`` of ``batch`` (the fit's scratch, its output, corners, shares): its
    offset and normals into the rows :func:`~translucency.scatter.fits.fitted_points` reads, its corners and their
    shares ``b_k weight``; returns ``queued + 1``."""
    pairs, corners, shares = batch[0][0], batch[2], batch[3]
    i0, i1, i2 = tri[0], tri[1], tri[2]
    m0 = b0 * normals[i0, 0] + b1 * normals[i1, 0] + b2 * normals[i2, 0]
    m1 = b0 * normals[i0, 1] + b1 * normals[i1, 1] + b2 * normals[i2, 1]
    m2 = b0 * normals[i0, 2] + b1 * normals[i1, 2] + b2 * normals[i2, 2]
    mn = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    if mn <= 0.0:
        m0, m1, m2, mn = 0.0, 0.0, 1.0, 1.0
    for t in range(3):
        pairs[t, queued] = xo[t] - (b0 * points[i0, t] + b1 * points[i1, t] + b2 * points[i2, t])
        pairs[6 + t, queued] = no[t]
    pairs[3, queued] = m0 / mn
    pairs[4, queued] = m1 / mn
    pairs[5, queued] = m2 / mn
    corners[queued, 0], corners[queued, 1], corners[queued, 2] = i0, i1, i2
    shares[queued, 0], shares[queued, 1], shares[queued, 2] = b0 * weight, b1 * weight, b2 * weight
    return queued + 1


@numba.njit(cache=True, fastmath=True, nogil=True)
def _flush_points(model, queued, params, dirs, pinv, batch, vertex_areas, slot, out):
    """Fit the ``queued`` points of ``batch`` (:func:`_queue_point`; :func:`~translucency.scatter.fits.fitted_points`)
    and add each point's coefficients to its corners' rows of ``out`` (``slot``: each vertex's row), shared by
    ``b_k / A_k`` (per unit flux of the corner); returns 0, the queue's new length."""
    if queued == 0:
        return np.int64(0)
    scratch, fitted, corners, shares = batch
    fitted_points(model, queued, params, dirs, pinv, scratch, fitted)
    for q in range(queued):
        for corner in range(3):
            v = corners[q, corner]
            share = shares[q, corner]
            if share == 0.0 or vertex_areas[v] <= 0.0:
                continue
            share /= vertex_areas[v]
            row = out[slot[v]]
            for c in range(params.shape[0]):
                for t in range(QUADRATIC_TERMS):
                    row[c * QUADRATIC_TERMS + t] += share * fitted[q, c, t]
    return np.int64(0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _operator_rows(
    worker,
    lo,
    hi,
    model,
    points,
    triangles,
    triangle_areas,
    normals,
    vertex_areas,
    receivers,
    offsets,
    triangle_ids,
    params,
    beta,
    scale_min,
    diameters,
    centroids,
    degree3,
    rule_points,
    rule_weights,
    ang_x,
    ang_w,
    rad_x,
    rad_w,
    dirs_q,
    pinv_q,
    stamps,
    starts,
    columns,
    coefs,
):
    """Rows of :func:`near_field_operator` for receivers ``lo .. hi - 1``: the near triangles' quadrature
    less their vertex rule, plus the near vertices' own pairs of the vertex sum; accumulated in float64,
    stored as float32. ``degree3``: the degree-3 rule's ratio and widest triangle (:func:`by_degree3`), the
    triangles' edges (``edge_of_corner``) and each thread's edge stamps (receiver, then the midpoint's slot)."""
    degree3_ratio, degree3_diameter, edge_of_corner, edge_stamps = degree3
    n_e = edge_stamps.shape[1] // 2
    edge_owner = edge_stamps[worker, :n_e]
    edge_slot = edge_stamps[worker, n_e:]
    mid_ends = np.empty((64, 2), dtype=np.int64)  # per midpoint of a degree-3 triangle's edge: its two vertices
    mid_weights = np.empty(64)  # and its weight, mm^2
    n_v = points.shape[0]
    n_c = params.shape[0]
    width = QUADRATIC_TERMS * n_c
    n_rule = rule_points.shape[0]
    owner = stamps[worker, :n_v]
    slot = stamps[worker, n_v:]
    stack = np.empty((3 * MAX_DEPTH + 8, 7))
    cx = np.empty((3, 3))
    found = np.empty((4**6, 7))
    own = np.empty((4 * ang_x.shape[0] * rad_x.shape[0], 4))
    batch = (  # the points waiting to be fitted (_queue_point): the fit's scratch, its output, corners, shares
        run_scratch(dirs_q.shape[0], np.int64(POINT_BATCH)),
        np.empty((POINT_BATCH, n_c, QUADRATIC_TERMS)),
        np.empty((POINT_BATCH, 3), dtype=np.int64),
        np.empty((POINT_BATCH, 3)),
    )
    queued = np.int64(0)
    acc = np.zeros((64, width))
    rule = np.zeros(64)  # per listed vertex: its share of the near triangles' vertex rule, mm^2
    one = np.empty(3, dtype=np.int64)  # a vertex as a degenerate triangle (its own point)
    for r in range(lo, hi):
        v_o = receivers[r]
        xo = points[v_o]
        no = normals[v_o]
        size = starts[r + 1] - starts[r]
        if acc.shape[0] < size:
            acc = np.zeros((2 * size, width))
        acc[:size] = 0.0
        if rule.shape[0] < size:
            rule = np.zeros(2 * size)
        listed = 0
        n_mid = 0
        for k in range(offsets[r], offsets[r + 1]):
            t = triangle_ids[k]
            third = triangle_areas[t] / 3.0
            for corner in range(3):
                v = triangles[t, corner]
                if owner[v] != r:
                    owner[v] = r
                    slot[v] = listed
                    columns[starts[r] + listed] = v
                    rule[listed] = 0.0
                    listed += 1
                rule[slot[v]] += third  # the vertex rule: a third of the area at each corner
            if corner_of(triangles[t], v_o) < 0 and by_degree3(
                diameters[t], centroids[t], xo, degree3_ratio, degree3_diameter, scale_min
            ):  # the degree-3 rule: its corners on the vertices' own points, each edge's midpoint listed once
                area = triangle_areas[t]
                if mid_weights.shape[0] < n_mid + 3:
                    mid_ends = np.concatenate((mid_ends, np.empty_like(mid_ends)))
                    mid_weights = np.concatenate((mid_weights, np.empty_like(mid_weights)))
                for corner in range(3):
                    rule[slot[triangles[t, corner]]] -= CORNER_WEIGHT * area
                    e = edge_of_corner[t, corner]
                    if edge_owner[e] != r:
                        edge_owner[e] = r
                        edge_slot[e] = n_mid
                        mid_ends[n_mid, 0] = triangles[t, corner]
                        mid_ends[n_mid, 1] = triangles[t, (corner + 1) % 3]
                        mid_weights[n_mid] = 0.0
                        n_mid += 1
                    mid_weights[edge_slot[e]] += MIDPOINT_WEIGHT * area
        # every near vertex once: its pair of the vertex sum less the vertex rule of the near triangles around it
        # (nothing where all its triangles are near), with the degree-3 rule's corners, with the quadratic fit
        for i in range(listed):
            v = columns[starts[r] + i]
            one[:] = v
            queued = _queue_point(points, normals, one, 1.0, 0.0, 0.0, vertex_areas[v] - rule[i], xo, no, batch, queued)
            if queued == POINT_BATCH:
                queued = _flush_points(model, queued, params, dirs_q, pinv_q, batch, vertex_areas, slot, acc)
        for i in range(n_mid):  # the degree-3 rule's midpoints
            one[0], one[1], one[2] = mid_ends[i, 0], mid_ends[i, 1], mid_ends[i, 0]
            queued = _queue_point(points, normals, one, 0.5, 0.5, 0.0, mid_weights[i], xo, no, batch, queued)
            if queued == POINT_BATCH:
                queued = _flush_points(model, queued, params, dirs_q, pinv_q, batch, vertex_areas, slot, acc)
        for k in range(offsets[r], offsets[r + 1]):
            t = triangle_ids[k]
            tri = triangles[t]
            area = triangle_areas[t]
            corner = corner_of(tri, v_o)
            if corner < 0 and by_degree3(diameters[t], centroids[t], xo, degree3_ratio, degree3_diameter, scale_min):
                third = 1.0 / 3.0  # the degree-3 rule's centroid
                queued = _queue_point(
                    points, normals, tri, third, third, third, CENTROID_WEIGHT * area, xo, no, batch, queued
                )
                if queued == POINT_BATCH:
                    queued = _flush_points(model, queued, params, dirs_q, pinv_q, batch, vertex_areas, slot, acc)
                continue
            if corner < 0 and integrated_whole(diameters[t], centroids[t], xo, beta, scale_min):
                for q in range(n_rule):
                    queued = _queue_point(
                        points,
                        normals,
                        tri,
                        rule_points[q, 0],
                        rule_points[q, 1],
                        rule_points[q, 2],
                        area * rule_weights[q],
                        xo,
                        no,
                        batch,
                        queued,
                    )
                    if queued == POINT_BATCH:
                        queued = _flush_points(model, queued, params, dirs_q, pinv_q, batch, vertex_areas, slot, acc)
                continue
            n, own, found = _own_points(
                points,
                tri,
                area,
                corner,
                xo,
                beta,
                scale_min,
                rule_points,
                rule_weights,
                ang_x,
                ang_w,
                rad_x,
                rad_w,
                stack,
                cx,
                found,
                own,
            )
            for j in range(n):
                queued = _queue_point(
                    points, normals, tri, own[j, 0], own[j, 1], own[j, 2], own[j, 3], xo, no, batch, queued
                )
                if queued == POINT_BATCH:
                    queued = _flush_points(model, queued, params, dirs_q, pinv_q, batch, vertex_areas, slot, acc)
        queued = _flush_points(model, queued, params, dirs_q, pinv_q, batch, vertex_areas, slot, acc)
        for i in range(size):
            for j in range(width):
                coefs[starts[r] + i, j] = acc[i, j]


#: The compiled kernels of the near field's lists and quadrature, and its operator rows for relighting: numba compiles
#: each on first use; the set-up compiles them ahead
#: (:mod:`translucency.app.warmup`).
NEAR_FIELD_KERNELS = (
    _near_pass,
    _vertex_triangles,
    _listed_once,
    _numbered_columns,
    _points_near,
    _fill_shared_points,
    _list_points,
    _refined_points,
    _operator_rows,
)
