"""Near-field surface integration: the part of B(x_o) that a vertex sum gets wrong.

The solver's answer is the surface integral ``B(x_o) = integral S_d(x, w12(x); x_o) phi(x) dA(x)``
(DESIGN.md, "Fast and accurate"). Summing over vertices, ``sum_j S_d(x_j; x_o) phi_j A_j``, is the
integral with a three-vertex rule on every triangle (``A_j`` is one third of the adjacent triangle
areas). That rule is accurate for triangles far from ``x_o`` compared with their size and with the
diffusion coefficient ``D`` -- and badly wrong near ``x_o``, where ``S_d`` varies on the scale ``D``
(0.1-0.5 mm for real materials) and the self term ``S_d(x_o; x_o)`` is counted with a whole vertex
area. So, for every receiver, the triangles within a near radius get a correction::

    C(x_o) = sum_{T near x_o} [ Q_T(f) - (A_T / 3) sum_{k in T} f(x_k) ],   f = S_d(.; x_o) phi

where ``Q_T`` is an adaptive quadrature over the triangle: midpoint subdivision into four until a
piece's diameter ``h`` satisfies ``h <= beta * max(dist, D_min)`` (``dist`` = distance from ``x_o`` to the
piece's centroid), then the 7-point degree-5 rule of Dunavant (1985) on each piece. Position, normal
and flux density are interpolated linearly over the triangle (the normal renormalised), the refracted
direction flux-weighted. ``B = vertex sum + C`` is then the surface integral, whatever the tessellation.

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

import numba
import numpy as np
from scipy.spatial import cKDTree

from .kernels import channel_lanes, indexed_sum

# Dunavant (1985) 7-point rule, exact for polynomials of degree 5: barycentric points and weights
# (weights sum to 1; multiply by the area).
_A1, _B1 = 0.059715871789770, 0.470142064105115
_A2, _B2 = 0.797426985353087, 0.101286507323456
_W1, _W2 = 0.132394152788506, 0.125939180544827
RULE_POINTS = np.array(
    [[1 / 3, 1 / 3, 1 / 3], [_A1, _B1, _B1], [_B1, _A1, _B1], [_B1, _B1, _A1], [_A2, _B2, _B2], [_B2, _A2, _B2], [_B2, _B2, _A2]]
)
RULE_WEIGHTS = np.array([0.225, _W1, _W1, _W1, _W2, _W2, _W2])

MAX_DEPTH = 14  # pieces as small as 4^-14 of the triangle's area


def near_triangles(points, triangles, receivers, radius):
    """For each receiver vertex, the triangles that have a vertex within ``radius`` (mm) of it.

    Includes the receiver's own 1-ring (the receiver is within any radius of itself).

    Returns
    -------
    offsets : (n_receivers + 1,) int64
    triangle_ids : (offsets[-1],) int64
        CSR lists: the near triangles of receiver ``r`` are ``triangle_ids[offsets[r]:offsets[r+1]]``.
    """
    n = points.shape[0]
    receivers = np.asarray(receivers, dtype=np.int64)
    # vertex -> incident triangles (CSR)
    corner_vertex = triangles.ravel()
    order = np.argsort(corner_vertex, kind="stable")
    vt_tris = (order // 3).astype(np.int64)
    vt_offsets = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(corner_vertex, minlength=n), out=vt_offsets[1:])
    # receiver -> vertices within the radius (itself included, at distance 0), as CSR
    found = cKDTree(points[receivers]).sparse_distance_matrix(cKDTree(points), radius, output_type="ndarray")
    rcv = np.concatenate([found["i"].astype(np.int64), np.arange(receivers.size)])
    vtx = np.concatenate([found["j"].astype(np.int64), receivers])
    by_receiver = np.argsort(rcv, kind="stable")
    near_vertices = vtx[by_receiver]
    nv_offsets = np.zeros(receivers.size + 1, dtype=np.int64)
    np.cumsum(np.bincount(rcv, minlength=receivers.size), out=nv_offsets[1:])
    return _incident_triangles(nv_offsets, near_vertices, vt_offsets, vt_tris, triangles.shape[0])


@numba.njit(cache=True)
def _incident_triangles(nv_offsets, near_vertices, vt_offsets, vt_tris, n_triangles):
    """Deduplicated union of the triangles incident to each receiver's near vertices (CSR in, CSR out)."""
    n_r = nv_offsets.shape[0] - 1
    bound = 0
    for q in range(near_vertices.shape[0]):
        bound += vt_offsets[near_vertices[q] + 1] - vt_offsets[near_vertices[q]]
    ids = np.empty(bound, dtype=np.int64)
    offsets = np.zeros(n_r + 1, dtype=np.int64)
    stamp = np.full(n_triangles, -1, dtype=np.int64)
    pos = 0
    for r in range(n_r):
        for q in range(nv_offsets[r], nv_offsets[r + 1]):
            v = near_vertices[q]
            for k in range(vt_offsets[v], vt_offsets[v + 1]):
                t = vt_tris[k]
                if stamp[t] != r:
                    stamp[t] = r
                    ids[pos] = t
                    pos += 1
        offsets[r + 1] = pos
    return offsets, ids[:pos].copy()


@numba.njit(cache=True, fastmath=True)
def _gather(points, normals, w12, phi, tri, b0, b1, b2, weight, buf, weights, column):
    """Write the point with barycentric ``b`` of triangle ``tri`` to column ``column`` of the buffer.

    ``buf[:, column]`` = position (3), normal (3, renormalised), refracted direction (3, flux-weighted
    and renormalised); ``weights[c, column] = weight * phi_c(b)`` (phi interpolated linearly). Where
    no light enters, the weights are 0 and the point is a harmless copy of the first corner (normal
    ``n``, direction ``-n``), so that evaluating it gives a finite 0.
    """
    a, b, c = tri[0], tri[1], tri[2]
    n_out = phi.shape[1]
    fa = 0.0
    fb = 0.0
    fc = 0.0
    for ch in range(n_out):
        fa += phi[a, ch]
        fb += phi[b, ch]
        fc += phi[c, ch]
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


def source_point_table(points, normals, w12, phi, triangles, triangle_areas, rule_points=RULE_POINTS,
                       rule_weights=RULE_WEIGHTS):
    """Quadrature points every receiver shares: the vertices, then the rule points of each lit triangle.

    Columns ``0..n-1`` are the vertices (weight ``phi``; the vertex rule's area factor is applied per
    receiver), then ``len(rule_points)`` columns per triangle with light at a corner (weight
    ``area * w_q * phi(x_q)``), made as :func:`_gather` makes them.

    Returns
    -------
    table : (9, P) float64
        Position (mm), unit normal, unit refracted direction of each point.
    weights : (C, P) float64
    vertex_lit : (n,) bool
        Whether light enters at the vertex.
    first_rule : (m,) int64
        Column of triangle ``t``'s first rule point, or -1 where no light enters at any corner.
    """
    n = points.shape[0]
    vertex_lit = phi.sum(axis=1) > 0
    lit_triangles = np.flatnonzero(vertex_lit[triangles].any(axis=1))
    n_rule = rule_points.shape[0]
    first_rule = np.full(triangles.shape[0], -1, dtype=np.int64)
    first_rule[lit_triangles] = n + n_rule * np.arange(lit_triangles.size)
    table = np.zeros((9, n + n_rule * lit_triangles.size))
    weights = np.zeros((phi.shape[1], table.shape[1]))
    table[0:3, :n] = points.T
    table[3:6, :n] = normals.T
    table[6:9, :n] = w12.T
    weights[:, :n] = phi.T
    _fill_rule_points(points, normals, w12, phi, triangles, triangle_areas, rule_points, rule_weights, lit_triangles,
                      table, weights, n)
    return table, weights, vertex_lit, first_rule


@numba.njit(cache=True, parallel=True)
def _fill_rule_points(points, normals, w12, phi, triangles, triangle_areas, rule_points, rule_weights, lit_triangles,
                      table, weights, start):
    """Rule points of the lit triangles into ``table``/``weights`` from column ``start`` on."""
    n_rule = rule_points.shape[0]
    for k in numba.prange(lit_triangles.shape[0]):
        t = lit_triangles[k]
        column = start + k * n_rule
        for q in range(n_rule):
            _gather(points, normals, w12, phi, triangles[t], rule_points[q, 0], rule_points[q, 1], rule_points[q, 2],
                    triangle_areas[t] * rule_weights[q], table, weights, column + q)


@numba.njit(cache=True, inline="always")
def _whole(diameter, centroid, xo, beta, scale_min):
    """Whether a triangle is far enough from ``x_o`` to be integrated whole with the rule (the
    refinement test of :func:`_pieces` applied to the triangle itself)."""
    d2 = 0.0
    for i in range(3):
        d2 += (centroid[i] - xo[i]) ** 2
    return diameter <= beta * max(math.sqrt(d2), scale_min)


@numba.njit(cache=True, fastmath=True)
def _pieces(points, tri, xo, beta, scale_min, stack, cx, out):
    """Adaptive midpoint subdivision of a triangle that is too close to be integrated whole.

    A piece is accepted when its diameter is at most ``beta * max(distance to x_o, scale_min)`` (or at
    depth :data:`MAX_DEPTH`). Writes the accepted pieces to ``out`` (rows: barycentric ``(b0, b1)`` of
    the three corners, then depth) when ``out`` has room, and returns how many there are.
    """
    a, b, c = tri[0], tri[1], tri[2]
    top = 0
    for child in ((1.0, 0.0, 0.5, 0.5, 0.5, 0.0), (0.5, 0.5, 0.0, 1.0, 0.0, 0.5), (0.5, 0.0, 0.0, 0.5, 0.0, 0.0),
                  (0.5, 0.5, 0.0, 0.5, 0.5, 0.0)):  # the four children of the whole triangle
        for i in range(6):
            stack[top, i] = child[i]
        stack[top, 6] = 1.0
        top += 1
    n = 0
    while top > 0:
        top -= 1
        p0, q0, p1, q1, p2, q2, depth = (stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3], stack[top, 4],
                                         stack[top, 5], stack[top, 6])
        r0 = 1.0 - p0 - q0
        r1 = 1.0 - p1 - q1
        r2 = 1.0 - p2 - q2
        for i in range(3):
            cx[0, i] = p0 * points[a, i] + q0 * points[b, i] + r0 * points[c, i]
            cx[1, i] = p1 * points[a, i] + q1 * points[b, i] + r1 * points[c, i]
            cx[2, i] = p2 * points[a, i] + q2 * points[b, i] + r2 * points[c, i]
        h2 = 0.0
        for (u, v) in ((0, 1), (1, 2), (2, 0)):
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
            children = ((p0, q0, m01p, m01q, m20p, m20q), (m01p, m01q, p1, q1, m12p, m12q),
                        (m20p, m20q, m12p, m12q, p2, q2), (m01p, m01q, m12p, m12q, m20p, m20q))
            for child in children:
                for i in range(6):
                    stack[top, i] = child[i]
                stack[top, 6] = depth + 1.0
                top += 1
    return n


def near_field_correction(model, points, triangles, triangle_areas, normals, w12, phi, receivers, offsets,
                          triangle_ids, params, channel_of, beta, scale_min, rule_points=RULE_POINTS,
                          rule_weights=RULE_WEIGHTS):
    """Correction ``C[r, c]`` of the vertex sum for every receiver ``r`` (see the module docstring).

    Receivers are done in blocks of :data:`BLOCK_RECEIVERS`: (1) list each receiver's quadrature
    points -- the vertex rule of its near triangles (each vertex once, weighted by the sum of the near
    triangles' thirds), the shared rule points of the triangles far enough to be integrated whole, and a
    count of the refined pieces of the closer ones; (2) make the refined points; (3) evaluate every
    receiver's points with :func:`~translucency.scatter.kernels.indexed_sum` (where the time goes).

    Returns
    -------
    correction : (n_receivers, C) float64
    pieces : (n_receivers,) int64
        Number of quadrature pieces (whole triangles and refined pieces) per receiver.
    """
    from ..io.geometry import edge_lengths

    table, weights, vertex_lit, first_rule = source_point_table(points, normals, w12, phi, triangles, triangle_areas,
                                                                rule_points, rule_weights)
    diameters = edge_lengths(points, triangles).max(axis=1)
    centroids = points[triangles].mean(axis=1)
    lanes = channel_lanes(params, channel_of, phi.shape[1])
    n_r = receivers.shape[0]
    correction = np.zeros((n_r, phi.shape[1]))
    pieces = np.zeros(n_r, dtype=np.int64)
    near_count = np.diff(offsets)
    chunks = 16 * numba.get_num_threads()
    for start in range(0, n_r, BLOCK_RECEIVERS):
        block = slice(start, min(n_r, start + BLOCK_RECEIVERS))
        rcv = receivers[block]
        col_offsets = np.zeros(rcv.size + 1, dtype=np.int64)
        np.cumsum((3 + rule_points.shape[0]) * near_count[block], out=col_offsets[1:])
        columns = np.empty(col_offsets[-1], dtype=np.int64)
        factors = np.empty(col_offsets[-1])
        n_columns = np.zeros(rcv.size, dtype=np.int64)
        n_refined = np.zeros(rcv.size, dtype=np.int64)
        _list_points(points, triangles, triangle_areas, rcv, offsets[start:block.stop + 1], triangle_ids, beta,
                     scale_min, vertex_lit, first_rule, diameters, centroids, col_offsets, columns, factors, n_columns,
                     n_refined, pieces[block], min(rcv.size, chunks))
        ref_offsets = np.zeros(rcv.size + 1, dtype=np.int64)
        np.cumsum(n_refined * rule_points.shape[0], out=ref_offsets[1:])
        refined = np.zeros((9, ref_offsets[-1]))
        refined_weights = np.zeros((phi.shape[1], ref_offsets[-1]))
        _refined_points(points, normals, w12, phi, triangles, triangle_areas, rcv, offsets[start:block.stop + 1],
                        triangle_ids, beta, scale_min, first_rule, diameters, centroids, rule_points, rule_weights,
                        ref_offsets, refined, refined_weights, min(rcv.size, chunks))
        rcv_points, rcv_normals = points[rcv], normals[rcv]
        correction[block] = (
            indexed_sum(model, rcv_points, rcv_normals, table, weights, col_offsets[:-1], n_columns, columns, factors,
                        params, lanes, channel_of)
            + indexed_sum(model, rcv_points, rcv_normals, refined, refined_weights, ref_offsets[:-1],
                          np.diff(ref_offsets), np.arange(ref_offsets[-1]), np.ones(ref_offsets[-1]), params, lanes,
                          channel_of))
    return correction, pieces


#: Receivers whose quadrature points are listed at a time (bounds the memory: ~150 KB per receiver).
BLOCK_RECEIVERS = 2048


@numba.njit(cache=True, parallel=True)
def _list_points(points, triangles, triangle_areas, receivers, offsets, triangle_ids, beta, scale_min, vertex_lit,
                 first_rule, diameters, centroids, col_offsets, columns, factors, n_columns, n_refined, pieces,
                 n_chunks):
    """Pass 1: per receiver, the shared-table points (vertex rule, whole triangles) and the refined count."""
    n_r = receivers.shape[0]
    n_v = points.shape[0]
    n_rule = RULE_POINTS.shape[0]
    for chunk in numba.prange(n_chunks):
        stack = np.empty((3 * MAX_DEPTH + 8, 7))
        cx = np.empty((3, 3))
        none = np.empty((0, 7))
        slot = np.full(n_v, -1, dtype=np.int64)  # position of a vertex in the receiver's list
        owner = np.full(n_v, -1, dtype=np.int64)
        for r in range(chunk * n_r // n_chunks, (chunk + 1) * n_r // n_chunks):
            xo = points[receivers[r]]
            base = col_offsets[r]
            listed = 0
            refined = 0
            count = 0
            for k in range(offsets[r], offsets[r + 1]):
                t = triangle_ids[k]
                if first_rule[t] < 0:  # no light enters at any corner: nothing to integrate
                    continue
                third = triangle_areas[t] / 3.0
                for corner in range(3):
                    v = triangles[t, corner]
                    if not vertex_lit[v]:
                        continue
                    if owner[v] != r:
                        owner[v] = r
                        slot[v] = listed
                        columns[base + listed] = v
                        factors[base + listed] = 0.0
                        listed += 1
                    factors[base + slot[v]] -= third
                if _whole(diameters[t], centroids[t], xo, beta, scale_min):  # the shared rule points
                    for q in range(n_rule):
                        columns[base + listed] = first_rule[t] + q
                        factors[base + listed] = 1.0
                        listed += 1
                    count += 1
                else:
                    used = _pieces(points, triangles[t], xo, beta, scale_min, stack, cx, none)
                    refined += used
                    count += used
            n_columns[r] = listed
            n_refined[r] = refined
            pieces[r] = count


@numba.njit(cache=True, parallel=True)
def _refined_points(points, normals, w12, phi, triangles, triangle_areas, receivers, offsets, triangle_ids, beta,
                    scale_min, first_rule, diameters, centroids, rule_points, rule_weights, ref_offsets, refined,
                    refined_weights, n_chunks):
    """Pass 2: the rule points of every refined piece, receiver by receiver from ``ref_offsets``."""
    n_r = receivers.shape[0]
    n_rule = rule_points.shape[0]
    for chunk in numba.prange(n_chunks):
        stack = np.empty((3 * MAX_DEPTH + 8, 7))
        cx = np.empty((3, 3))
        found = np.empty((4 ** 6, 7))
        for r in range(chunk * n_r // n_chunks, (chunk + 1) * n_r // n_chunks):
            xo = points[receivers[r]]
            column = ref_offsets[r]
            for k in range(offsets[r], offsets[r + 1]):
                t = triangle_ids[k]
                if first_rule[t] < 0:
                    continue
                if _whole(diameters[t], centroids[t], xo, beta, scale_min):
                    continue
                n = _pieces(points, triangles[t], xo, beta, scale_min, stack, cx, found)
                if n > found.shape[0]:  # deeper than the scratch space: grow it and subdivide again
                    found = np.empty((n, 7))
                    n = _pieces(points, triangles[t], xo, beta, scale_min, stack, cx, found)
                tri = triangles[t]
                for j in range(n):
                    p0, q0, p1, q1, p2, q2 = found[j, 0], found[j, 1], found[j, 2], found[j, 3], found[j, 4], found[j, 5]
                    r0 = 1.0 - p0 - q0
                    r1 = 1.0 - p1 - q1
                    r2 = 1.0 - p2 - q2
                    piece_area = triangle_areas[t] * 0.25 ** found[j, 6]
                    for qp in range(n_rule):
                        l0 = rule_points[qp, 0]
                        l1 = rule_points[qp, 1]
                        l2 = rule_points[qp, 2]
                        _gather(points, normals, w12, phi, tri, l0 * p0 + l1 * p1 + l2 * p2, l0 * q0 + l1 * q1 + l2 * q2,
                                l0 * r0 + l1 * r1 + l2 * r2, piece_area * rule_weights[qp], refined, refined_weights,
                                column)
                        column += 1
