"""The near field's correction on an NVIDIA GPU: each receiver's quadrature over its near triangles (docs/physics.md
§8.2), made and summed by one thread.

The CPU lists the points every receiver shares (the vertices, the whole triangles' rule points) once per block and
each receiver's own points (the fan rule on its own triangles, the refined pieces of the close ones) apart, then sums
the lists (:func:`translucency.scatter.nearfield.near_field_correction`); 90 % of its time is the listing. A GPU
thread cannot grow a list, so each makes its receiver's points as it goes and sums them at once: per near triangle
with light, the vertex rule taken off (``-A/3`` at each lit corner), then the fan rule (own triangle), Dunavant's rule
whole, or Dunavant's rule on the pieces of the subdivision, with the CPU's own functions
(:func:`~translucency.scatter.nearfield.fan_rule`, :func:`~translucency.scatter.nearfield.subdivided_pieces`,
:func:`~translucency.scatter.nearfield.gather_point`, ...) and pair
(:func:`~translucency.scatter.kernels.weighted_pair`).
These are ``exact``'s rules: the CPU's ``tree`` and ``cutoff`` put the cheaper degree-3 rule on some whole triangles,
the GPU does not (its answer is ``exact``'s near field, to rounding). A receiver whose fan or subdivision would
overflow the thread's scratch space is left to the CPU.

========== ===================================================================== =====
symbol     meaning                                                               unit
========== ===================================================================== =====
phi        flux density entering at each vertex, per output channel              flux / mm^2
offsets    receiver ``r``'s near triangles: ``triangle_ids[offsets[r] : offsets[r + 1]]``
========== ===================================================================== =====
"""

from __future__ import annotations

import numpy as np
from numba import cuda, float64

from .. import kernels, nearfield
from .compiled import for_the_device, lane_groups, to_device
from .probe import said_plainly

__all__ = ["near_field_correction", "release"]


_pair = for_the_device(kernels.weighted_pair)
_gather = for_the_device(nearfield.gather_point, "corner_flux")
_whole = for_the_device(nearfield.integrated_whole)
_corner_of = for_the_device(nearfield.corner_of)
_pieces = for_the_device(nearfield.subdivided_pieces)
_piece_point = for_the_device(nearfield.piece_point)
_fan_count = for_the_device(nearfield.fan_count, "corner_frame")
_fan = for_the_device(nearfield.fan_rule, "corner_frame")

#: Threads per block.
THREADS = 64
#: A thread's scratch space: rows of the fan rule on one triangle, pieces of one subdivision, output channels of
#: the flux (a receiver whose triangle needs more is left to the CPU), and the subdivision's stack.
FAN_ROWS = 256
PIECES = 256
MAX_CHANNELS = 8
STACK_ROWS = 3 * nearfield.MAX_DEPTH + 8
#: How a triangle is integrated: the fan rule, Dunavant's rule whole, or on the pieces of the subdivision.
FAN, WHOLE, PIECES_RULE = 0, 1, 2


@cuda.jit
def _near_sums(
    model, surface, light, tables, receivers, lists, rules, scales, lanes, lane_channels, out, counts, overflow
):
    """Thread ``r``: receiver ``r``'s near-field correction of three lanes (parameters ``lanes``, output channels
    ``lane_channels`` of ``phi``). ``surface`` is ``(points, normals, triangles, triangle_areas)``, ``light``
    ``(w12, phi)``, ``tables`` ``(diameters, centroids)``, ``lists`` ``(offsets, triangle_ids)``, ``rules``
    Dunavant's ``(points, weights)`` and the fan's ``(angular nodes, weights, radial nodes, weights)``, ``scales``
    ``(beta, D_min mm)``. Writes ``out[r]`` and the points it evaluated to ``counts[r]``, or sets ``overflow[r]``
    where the scratch space is too small."""
    r = cuda.grid(1)
    if r >= receivers.shape[0]:
        return
    points, normals, triangles, areas = surface
    w12, phi = light
    diameters, centroids = tables
    offsets, triangle_ids = lists
    rule_points, rule_weights, ang_x, ang_w, rad_x, rad_w = rules
    beta, scale_min = scales
    k0, k1, k2 = lane_channels
    n_rule = rule_points.shape[0]
    n_out = phi.shape[1]
    v_o = receivers[r]
    xo = points[v_o]
    x0, x1, x2 = xo[0], xo[1], xo[2]
    n_o = (normals[v_o, 0], normals[v_o, 1], normals[v_o, 2])
    buf = cuda.local.array((9, 1), float64)
    weights = cuda.local.array((MAX_CHANNELS, 1), float64)
    stack = cuda.local.array((STACK_ROWS, 7), float64)
    cx = cuda.local.array((3, 3), float64)
    found = cuda.local.array((PIECES, 7), float64)
    fan = cuda.local.array((FAN_ROWS, 4), float64)
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    evaluated = 0
    for k in range(offsets[r], offsets[r + 1]):
        t = triangle_ids[k]
        tri = triangles[t]
        area = areas[t]
        lit = False
        for corner in range(3):
            for c in range(n_out):
                if phi[tri[corner], c] != 0.0:
                    lit = True
        if not lit:  # no light enters at any corner: nothing to integrate
            continue
        corner = _corner_of(tri, v_o)
        if corner >= 0:  # the receiver's own triangle: the fan rule
            rule = FAN
            n = _fan_count(points, tri, corner, beta * scale_min, ang_x.shape[0], rad_x.shape[0])
            if n > FAN_ROWS:
                overflow[r] = 1
                return
            _fan(points, tri, corner, beta, scale_min, ang_x, ang_w, rad_x, rad_w, fan)
        elif _whole(diameters[t], centroids[t], xo, beta, scale_min):
            rule = WHOLE
            n = n_rule
        else:  # the pieces of the subdivision, Dunavant's rule on each
            rule = PIECES_RULE
            n = _pieces(points, tri, xo, beta, scale_min, stack, cx, found)
            if n > PIECES:
                overflow[r] = 1
                return
            n *= n_rule
        for m in range(-3, n):  # the three corners' vertex rule, taken off, then the rule's points
            if m < 0:
                b0 = 1.0 if m == -3 else 0.0
                b1 = 1.0 if m == -2 else 0.0
                b2 = 1.0 if m == -1 else 0.0
                weight = -area / 3.0
            elif rule == FAN:
                b0, b1, b2, weight = fan[m, 0], fan[m, 1], fan[m, 2], fan[m, 3] * area
            elif rule == WHOLE:
                b0, b1, b2 = rule_points[m, 0], rule_points[m, 1], rule_points[m, 2]
                weight = area * rule_weights[m]
            else:
                j = m // n_rule
                q = m - j * n_rule
                corners = (found[j, 0], found[j, 1], found[j, 2], found[j, 3], found[j, 4], found[j, 5])
                b0, b1, b2 = _piece_point(corners, rule_points[q, 0], rule_points[q, 1], rule_points[q, 2])
                weight = area * 0.25 ** found[j, 6] * rule_weights[q]
            _gather(points, normals, w12, phi, tri, b0, b1, b2, weight, buf, weights, 0)
            e0, e1, e2, _ = _pair(
                model,
                (x0 - buf[0, 0], x1 - buf[1, 0], x2 - buf[2, 0]),
                (buf[3, 0], buf[4, 0], buf[5, 0], buf[6, 0], buf[7, 0], buf[8, 0]),
                n_o,
                lanes,
                (weights[k0, 0], weights[k1, 0], weights[k2, 0]),
                (0, 0, 0),
            )
            a0 += e0
            a1 += e1
            a2 += e2
        evaluated += 3 + n
    out[r, 0] = a0
    out[r, 1] = a1
    out[r, 2] = a2
    counts[r] = evaluated


#: The mesh and the light on the device while a solve corrects its blocks of receivers one after another
#: (:func:`release` when it is done): ``{"host": the arrays they were copied from, "device": the copies}``.
_HELD: dict = {}


def _held(host: tuple) -> tuple:
    """``(surface, light, sizes)`` on the device for ``host`` = ``(points, normals, triangles, triangle_areas, w12,
    phi, tables)``: copied once for a solve's blocks (the same arrays, by identity), again for other arrays."""
    kept = _HELD.get("host")
    if kept is None or len(kept) != len(host) or any(a is not b for a, b in zip(kept, host)):
        points, normals, triangles, triangle_areas, w12, phi, tables = host
        _HELD["device"] = (
            (to_device(points), to_device(normals), to_device(triangles, np.int64), to_device(triangle_areas)),
            (to_device(w12), to_device(phi)),
            (to_device(tables.diameters), to_device(tables.centroids)),
        )
        _HELD["host"] = host
    return _HELD["device"]


def release() -> None:
    """Give back the device's copies of the last solve's mesh and light (:func:`near_field_correction` keeps them
    between the blocks of one solve)."""
    _HELD.clear()


@said_plainly
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
    tables,
):
    """:func:`translucency.scatter.nearfield.near_field_correction` with ``exact``'s rules (no degree-3 rule) on the
    GPU: the same arguments (positions mm, ``phi (n, C)``, ``receivers`` vertex indices and their near lists,
    ``tables`` the mesh's :class:`~translucency.scatter.nearfield.TriangleTables`). Returns ``(correction (n_r, C)
    float64, points evaluated per receiver)``; receivers the GPU's scratch space cannot hold are corrected on the
    CPU."""
    n_r, n_out = receivers.shape[0], phi.shape[1]
    cpu_args = (model, points, triangles, triangle_areas, normals, w12, phi)
    if n_r == 0 or n_out > MAX_CHANNELS:
        return nearfield.near_field_correction(
            *cpu_args, receivers, offsets, triangle_ids, params, channel_of, beta, scale_min, tables=tables
        )

    surface, light, sizes = _held((points, normals, triangles, triangle_areas, w12, phi, tables))
    lists = (to_device(offsets - offsets[0], np.int64), to_device(triangle_ids[offsets[0] : offsets[-1]], np.int64))
    fan = (*nearfield.gauss_legendre_unit(nearfield.FAN_ANGULAR), *nearfield.gauss_legendre_unit(nearfield.FAN_RADIAL))
    rules = tuple(to_device(a) for a in (nearfield.RULE_POINTS, nearfield.RULE_WEIGHTS, *fan))
    lanes = kernels.channel_lanes(params, channel_of, n_out)
    device_receivers = to_device(receivers, np.int64)
    part = cuda.device_array((n_r, 3), dtype=np.float64)
    counts = cuda.device_array(n_r, dtype=np.int64)
    overflow = cuda.to_device(np.zeros(n_r, dtype=np.int64))
    correction = np.empty((n_r, lanes.shape[0]))
    for launch, channels, lane_params in lane_groups(lanes, n_out):
        _near_sums[-(-n_r // THREADS), THREADS](
            int(model),
            surface,
            light,
            sizes,
            device_receivers,
            lists,
            rules,
            (float(beta), float(scale_min)),
            lane_params,
            channels,
            part,
            counts,
            overflow,
        )
        correction[:, launch.start : launch.stop] = part.copy_to_host()
    correction = np.ascontiguousarray(correction[:, :n_out])
    evaluated = counts.copy_to_host()
    left = np.flatnonzero(overflow.copy_to_host())
    if left.size:  # the CPU's, for the receivers whose fan or subdivision the GPU's scratch space could not hold
        first, last = offsets[left], offsets[left + 1]
        ids = np.concatenate([triangle_ids[a:b] for a, b in zip(first, last)])
        own_offsets = np.concatenate([[0], np.cumsum(last - first)])
        correction[left], evaluated[left] = nearfield.near_field_correction(
            *cpu_args, receivers[left], own_offsets, ids, params, channel_of, beta, scale_min, tables=tables
        )
    return correction, evaluated
