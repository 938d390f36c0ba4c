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

from .kernels import model_pair

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
def _integrand(model, points, normals, w12, phi, tri, b0, b1, b2, xo, no, params, channel_of, sd, out, weight):
    """Add ``weight * S_d(x(b); x_o) * phi(b)`` for every output channel to ``out`` (barycentric ``b``)."""
    a, b, c = tri[0], tri[1], tri[2]
    x0 = b0 * points[a, 0] + b1 * points[b, 0] + b2 * points[c, 0]
    x1 = b0 * points[a, 1] + b1 * points[b, 1] + b2 * points[c, 1]
    x2 = b0 * points[a, 2] + b1 * points[b, 2] + b2 * points[c, 2]
    m0 = b0 * normals[a, 0] + b1 * normals[b, 0] + b2 * normals[c, 0]
    m1 = b0 * normals[a, 1] + b1 * normals[b, 1] + b2 * normals[c, 1]
    m2 = b0 * normals[a, 2] + b1 * normals[b, 2] + b2 * normals[c, 2]
    mn = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    if mn > 0.0:
        m0 /= mn
        m1 /= mn
        m2 /= mn
    n_out = phi.shape[1]
    # flux-weighted refracted direction (weights: mean flux density over the channels)
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
    if wa + wb + wc <= 0.0:
        return
    v0 = wa * w12[a, 0] + wb * w12[b, 0] + wc * w12[c, 0]
    v1 = wa * w12[a, 1] + wb * w12[b, 1] + wc * w12[c, 1]
    v2 = wa * w12[a, 2] + wb * w12[b, 2] + wc * w12[c, 2]
    vn = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if vn <= 0.0:
        return
    model_pair(model, x0, x1, x2, m0, m1, m2, v0 / vn, v1 / vn, v2 / vn, xo[0], xo[1], xo[2], no[0], no[1], no[2],
                            params, sd)
    for ch in range(n_out):
        density = b0 * phi[a, ch] + b1 * phi[b, ch] + b2 * phi[c, ch]
        out[ch] += weight * sd[channel_of[ch]] * density


@numba.njit(cache=True, fastmath=True)
def _triangle_correction(model, points, normals, w12, phi, tri, area, xo, no, params, channel_of, beta, scale_min,
                         rule_points, rule_weights, sd, acc, stack, cx):
    """Add ``Q_T(f) - (A_T/3) sum_k f(x_k)`` of one triangle to ``acc``; returns the number of pieces."""
    n_out = acc.shape[0]
    # the three-vertex rule that the vertex sum applied to this triangle, subtracted
    third = -area / 3.0
    _integrand(model, points, normals, w12, phi, tri, 1.0, 0.0, 0.0, xo, no, params, channel_of, sd, acc, third)
    _integrand(model, points, normals, w12, phi, tri, 0.0, 1.0, 0.0, xo, no, params, channel_of, sd, acc, third)
    _integrand(model, points, normals, w12, phi, tri, 0.0, 0.0, 1.0, xo, no, params, channel_of, sd, acc, third)
    a, b, c = tri[0], tri[1], tri[2]
    # stack rows: barycentric (b0, b1) of the piece's three corners, then depth
    top = 0
    stack[0, 0] = 1.0
    stack[0, 1] = 0.0
    stack[0, 2] = 0.0
    stack[0, 3] = 1.0
    stack[0, 4] = 0.0
    stack[0, 5] = 0.0
    stack[0, 6] = 0.0
    top = 1
    pieces = 0
    while top > 0:
        top -= 1
        p0, q0, p1, q1, p2, q2, depth = (stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3], stack[top, 4],
                                         stack[top, 5], stack[top, 6])
        r0 = 1.0 - p0 - q0
        r1 = 1.0 - p1 - q1
        r2 = 1.0 - p2 - q2
        # world-space corners of the piece
        for i in range(3):
            cx[0, i] = p0 * points[a, i] + q0 * points[b, i] + r0 * points[c, i]
            cx[1, i] = p1 * points[a, i] + q1 * points[b, i] + r1 * points[c, i]
            cx[2, i] = p2 * points[a, i] + q2 * points[b, i] + r2 * points[c, i]
        h2 = 0.0
        for (u, v) in ((0, 1), (1, 2), (2, 0)):
            e = (cx[u, 0] - cx[v, 0]) ** 2 + (cx[u, 1] - cx[v, 1]) ** 2 + (cx[u, 2] - cx[v, 2]) ** 2
            if e > h2:
                h2 = e
        h = math.sqrt(h2)
        dist2 = 0.0
        for i in range(3):
            dist2 += ((cx[0, i] + cx[1, i] + cx[2, i]) / 3.0 - xo[i]) ** 2
        dist = max(math.sqrt(dist2), scale_min)
        if h <= beta * dist or depth >= MAX_DEPTH:
            pieces += 1
            piece_area = area * 0.25**depth
            for qp in range(rule_points.shape[0]):
                l0 = rule_points[qp, 0]
                l1 = rule_points[qp, 1]
                l2 = rule_points[qp, 2]
                _integrand(model, points, normals, w12, phi, tri,
                           l0 * p0 + l1 * p1 + l2 * p2, l0 * q0 + l1 * q1 + l2 * q2, l0 * r0 + l1 * r1 + l2 * r2,
                           xo, no, params, channel_of, sd, acc, piece_area * rule_weights[qp])
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
    return pieces


@numba.njit(cache=True, parallel=True)
def near_field_correction(model, points, triangles, triangle_areas, normals, w12, phi, receivers, offsets, triangle_ids, params,
                          channel_of, beta, scale_min, rule_points, rule_weights):
    """Correction ``C[r, c]`` of the vertex sum for every receiver ``r`` (see the module docstring).

    Returns
    -------
    correction : (n_receivers, C) float64
    pieces : (n_receivers,) int64
        Number of quadrature pieces used per receiver (cost and refinement diagnostics).
    """
    n_r = receivers.shape[0]
    n_out = phi.shape[1]
    correction = np.zeros((n_r, n_out))
    pieces = np.zeros(n_r, dtype=np.int64)
    for r in numba.prange(n_r):
        o = receivers[r]
        xo = points[o]
        no = normals[o]
        sd = np.empty(params.shape[0])
        acc = np.zeros(n_out)
        stack = np.empty((3 * MAX_DEPTH + 8, 7))
        cx = np.empty((3, 3))
        for k in range(offsets[r], offsets[r + 1]):
            t = triangle_ids[k]
            pieces[r] += _triangle_correction(model, points, normals, w12, phi, triangles[t], triangle_areas[t], xo, no, params,
                                              channel_of, beta, scale_min, rule_points, rule_weights, sd, acc, stack, cx)
        for ch in range(n_out):
            correction[r, ch] = acc[ch]
    return correction, pieces
