"""Path-traced radiance along the normal at points of a closed mesh: the ground truth for the models.

The object is the closed triangle mesh itself, flat facets with a smooth dielectric boundary of relative
index ``eta`` around a homogeneous medium (``sigma_a``, ``sigma_s``, Henyey-Greenstein ``g``), lit by
one directional light. For every sensor (a surface point and its outward normal) the walk estimates the
radiance leaving the surface along the normal that crossed the boundary from inside (the subsurface part;
the boundary's own reflection at the sensor is not included, as in the models), without bias
(docs/physics.md §9.5):

1. a path starts at the sensor point and travels along ``-n`` (the refraction of the normal
   direction is the normal itself), weight ``T21(eta, 1) / eta^2`` (what crosses outward, and the
   radiance of a ray entering the lower index divides by ``eta^2``);
2. free flights ``-ln(xi) / sigma_t`` in the medium against the first boundary hit (Embree); an
   interaction multiplies the weight by the albedo ``sigma_s / sigma_t``;
3. at every interaction ``z``, **next event through the refracting boundary**: the light enters a facet
   ``f`` facing it as a collimated beam along the refracted direction ``w_t(f)`` with flux density
   ``T12 cos_i / cos_t`` per unit irradiance across the beam, which is constant over the flat facet; ``z``
   is lit through ``f`` when the ray from ``z`` along ``-w_t(f)`` meets ``f`` first and the entry point
   sees the light. The facets are found by a fixed-point search (start with the facet toward the light,
   then follow ``-w_t`` of the last facet found) and then every facet around the last one is tested, so
   overlapping beams (a convex surface focuses the light) each count. The contribution is
   ``w p_HG(w_t . -d) (T12 cos_i / cos_t) exp(-sigma_t s) V`` with ``s`` the way from the entry point;
4. a new direction from Henyey-Greenstein; at the boundary, reflection with the Fresnel probability or
   refraction out (weight times ``eta^2``); outside, the path goes on to the next surface it meets
   (refraction in: weight over ``eta^2``, and everything found after that is light that **re-entered**)
   or leaves (the light is a delta direction and the surroundings are black: nothing more);
5. Russian roulette on small weights.

Each path is one independent sample per sensor, so the standard error is the sample standard deviation
over ``spp`` paths divided by ``sqrt(spp)``. Channels with different coefficients are walked apart.

What it leaves out: light reflected by the outer boundary before it enters (the mirror image of the light
on another part of the object; a few percent of the light in concavities), and light reflected inside
before its first interaction (the unscattered beam meeting the boundary again: ``exp(-sigma_t`` x
thickness``)``). Interactions deeper than ``NEE_MAX_OPTICAL_DEPTH / sigma_t`` from every facet the light
enters skip the next event: what they would add is below ``exp(-40)`` of the light that entered. Between
``NEE_FREE_OPTICAL_DEPTH`` and that depth the next event is taken at random, with a probability that falls as
what it can add, and weighted by its inverse (still unbiased; it saves most rays of the paths that wander
deep into a large object).

========== ================================================================ =========
symbol     meaning                                                          unit
========== ================================================================ =========
L          radiance leaving the surface along the normal (per E)            W/(m² sr)
E          irradiance of the light on a surface facing it                   W/m²
sigma_t    extinction coefficient sigma_a + sigma_s (unreduced)             1/mm
g          Henyey-Greenstein mean cosine                                    1
eta        relative index n_inside / n_outside                              1
w_L        unit direction toward the light                                  1
w_t(f)     refracted direction of the light entering facet f                1
s          distance from the entry point to the interaction                 mm
p_HG       Henyey-Greenstein phase function                                 1/sr
spp        paths per sensor and channel                                     1
========== ================================================================ =========
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numba
import numpy as np
from scipy.spatial import cKDTree

from ..errors import InvalidParameterError, MeshError
from ..geometry.measure import signed_volume, triangle_normals
from ..geometry.topology import boundary_loops, unique_edges
from ..scatter.budget import check_limits
from ..scatter.fresnel import fresnel_reflectance_scalar, fresnel_transmittance, refract
from ..scatter.kernels import orthonormal_frame
from ..scatter.medium import Medium
from ..scatter.montecarlo import sample_hg_cosine
from ..scatter.visibility import Occluder
from .trace_settings import WorkTally, check_seed, check_spp, check_time, progress_line

__all__ = ["ReferenceRadiance", "trace_radiance", "NEE_MAX_OPTICAL_DEPTH"]

#: An interaction farther than this many mean free paths ``1/sigma_t`` from every facet the light enters
#: skips the next event (it would add less than ``exp(-40)`` of the entering light) ...
NEE_MAX_OPTICAL_DEPTH = 40.0
#: ... and one farther than this takes it with probability ``exp(-(depth - NEE_FREE_OPTICAL_DEPTH))``.
NEE_FREE_OPTICAL_DEPTH = 4.0
#: Steps of the fixed-point search for the facet that lights an interaction (docs/physics.md §9.5).
NEE_SEARCH_STEPS = 4
#: Russian roulette below this fraction of the starting weight: survival 0.1, weight x 10.
ROULETTE_FRACTION = 1e-3
ROULETTE_SURVIVAL = 0.1
#: A path still walking after this many interactions is stopped and counted (never seen in practice).
MAX_INTERACTIONS = 1_000_000
#: Cells along the longest side of the grid that bounds the depth of interactions below the surface.
DEPTH_GRID_CELLS = 96
#: Paths in flight together; finished ones are replaced from the queue while it lasts.
PATHS_PER_WAVE = 1 << 17
#: Seconds between two progress reports.
PROGRESS_SECONDS = 2.0
#: Seconds of tracing after which the rate is known well enough to hold ``spp`` to the time limit.
CALIBRATION_SECONDS = 2.0

# Event codes of one flight.
_SCATTER = 0
_MOVED = 1
_ESCAPED = 2
_LEAKED = 3


@dataclass(frozen=True)
class ReferenceRadiance:
    """Path-traced radiance along the normal at each sensor, with standard errors.

    Attributes
    ----------
    radiance : ndarray, shape (k, C)
        Radiance leaving the surface along the normal, the subsurface part, W/(m² sr), for the
        irradiance given (docs/physics.md §9.5).
    radiance_stderr : ndarray, shape (k, C)
        Its standard error (sample standard deviation over the paths / sqrt(spp)), W/(m² sr).
    radiance_reentered : ndarray, shape (k, C)
        The part of ``radiance`` carried by light that left the surface and entered it again, W/(m² sr).
    spp : int
        Paths per sensor and channel.
    seconds : float
        Wall time of the walk, s.
    stats : dict
        Counters: ``paths``, ``interactions``, ``rays``, ``leaked_paths`` (a ray from inside met no
        surface or a surface from its outer side: an open or self-intersecting mesh), ``stopped_paths``
        (over ``MAX_INTERACTIONS``), ``next_event_skipped`` (too deep), ``flights_without_ray`` (shorter than
        the distance to every facet), ``entries_found`` (lit facets
        found by the next event).
    """

    radiance: np.ndarray
    radiance_stderr: np.ndarray
    radiance_reentered: np.ndarray
    spp: int
    seconds: float
    stats: dict = field(default_factory=dict)

    def relative_stderr(self, floor: float = 1e-3) -> float:
        """Median of ``radiance_stderr / radiance`` over the (sensor, channel) whose radiance is at least
        ``floor`` of the largest in its channel (1)."""
        return _median_relative_error(self.radiance, self.radiance_stderr, floor)


def _mean_and_stderr(sums, n: int):
    """Mean and standard error of the mean of ``n`` samples per entry from their sum and sum of squares."""
    mean = sums[0] / n
    return mean, np.sqrt(np.maximum(sums[1] / n - mean**2, 0.0) / (n - 1))


def _median_relative_error(mean, stderr, floor: float = 1e-3) -> float:
    """Median of ``stderr / mean`` over the entries whose mean is at least ``floor`` of the largest in its
    column (channel); inf when there is none."""
    keep = (mean >= floor * np.maximum(mean.max(axis=0, keepdims=True), 1e-300)) & (mean > 0)
    return float(np.median(stderr[keep] / mean[keep])) if np.any(keep) else math.inf


# --------------------------------------------------------------------------------------------------
# Kernels (numba): one flight, new directions, the facets around a facet whose beam holds a point
# --------------------------------------------------------------------------------------------------


@numba.njit(cache=True)
def _flight(
    x,
    d,
    skip,
    w,
    inside,
    reentered,
    channel,
    hit,
    hit_distance,
    xi_flight,
    xi_fresnel,
    face_normals,
    sigma_t,
    albedo,
    eta,
    eps,
):
    """One flight of every path in the wave, in place; returns the event code of each (docs/physics.md §9.5).

    Inside, a flight shorter than the way to the boundary ends in an interaction (weight x albedo, the
    direction kept for the next event); otherwise, and always outside, the path meets the boundary and is
    reflected (Fresnel probability) or refracted through it. A path on the boundary stays exactly there;
    its next ray is cast from ``skip`` further along its direction (``eps / |cos|``, so the ray cannot meet
    the facet it leaves) and ``hit_distance`` counts from ``x`` itself, so no medium is stepped over.
    """
    m = x.shape[0]
    event = np.empty(m, dtype=np.int8)
    eta2 = eta * eta
    for i in range(m):
        f = hit[i]
        if inside[i]:
            step = -math.log(xi_flight[i]) / sigma_t[channel[i]]
            if step < hit_distance[i]:
                for k in range(3):
                    x[i, k] += step * d[i, k]
                skip[i] = 0.0
                w[i] *= albedo[channel[i]]
                event[i] = _SCATTER
                continue
            if f < 0:
                event[i] = _LEAKED
                continue
        elif f < 0:
            event[i] = _ESCAPED
            continue
        nx, ny, nz = face_normals[f, 0], face_normals[f, 1], face_normals[f, 2]
        t = hit_distance[i]
        px = x[i, 0] + t * d[i, 0]
        py = x[i, 1] + t * d[i, 1]
        pz = x[i, 2] + t * d[i, 2]
        cos_out = d[i, 0] * nx + d[i, 1] * ny + d[i, 2] * nz  # > 0: leaving through the facet
        if inside[i]:
            if cos_out <= 0.0:
                event[i] = _LEAKED
                continue
            c = cos_out
            ratio = 1.0 / eta  # inside -> outside
            side = 1.0  # the transmitted side along +n
        else:
            if cos_out >= 0.0:
                event[i] = _LEAKED
                continue
            c = -cos_out
            ratio = eta
            side = -1.0
        reflectance = fresnel_reflectance_scalar(c, ratio)
        if xi_fresnel[i] < reflectance:
            # mirror reflection, stays on the same side
            d[i, 0] -= 2.0 * cos_out * nx
            d[i, 1] -= 2.0 * cos_out * ny
            d[i, 2] -= 2.0 * cos_out * nz
        else:
            # refraction (docs/physics.md §3.2): t = r d + (cos_t - r cos_i) n_side, r = n_i / n_t
            r = 1.0 / ratio
            cos_t = math.sqrt(max(0.0, 1.0 - r * r * (1.0 - c * c)))
            a = cos_t - r * c
            tx = r * d[i, 0] + a * side * nx
            ty = r * d[i, 1] + a * side * ny
            tz = r * d[i, 2] + a * side * nz
            length = math.sqrt(tx * tx + ty * ty + tz * tz)
            d[i, 0] = tx / length
            d[i, 1] = ty / length
            d[i, 2] = tz / length
            if inside[i]:
                w[i] *= eta2
                inside[i] = False
            else:
                w[i] /= eta2
                inside[i] = True
                reentered[i] = True
        x[i, 0] = px
        x[i, 1] = py
        x[i, 2] = pz
        cos_new = abs(d[i, 0] * nx + d[i, 1] * ny + d[i, 2] * nz)
        skip[i] = eps / max(cos_new, 1e-3)
        event[i] = _MOVED
    return event


@numba.njit(cache=True)
def _new_directions(d, rows, channel, g_of_channel, xi_cos, xi_phi):
    """Henyey-Greenstein directions about the current ones, in place for ``rows`` (docs/physics.md §9.1)."""
    for j in range(rows.shape[0]):
        i = rows[j]
        cos_theta = sample_hg_cosine(g_of_channel[channel[i]], xi_cos[j])
        sin_theta = math.sqrt(max(0.0, 1.0 - cos_theta * cos_theta))
        phi = 2.0 * math.pi * xi_phi[j]
        ux, uy, uz = d[i, 0], d[i, 1], d[i, 2]
        ax, ay, az, bx, by, bz = orthonormal_frame(ux, uy, uz)
        c = sin_theta * math.cos(phi)
        s = sin_theta * math.sin(phi)
        nx = cos_theta * ux + c * ax + s * bx
        ny = cos_theta * uy + c * ay + s * by
        nz = cos_theta * uz + c * az + s * bz
        length = math.sqrt(nx * nx + ny * ny + nz * nz)
        d[i, 0] = nx / length
        d[i, 1] = ny / length
        d[i, 2] = nz / length


@numba.njit(cache=True)
def _beam_candidates(z, facet, points, triangles, face_normals, w_t, lit_side, facet_start, facet_list):
    """Facets around ``facet[i]`` whose refracted beam holds ``z[i]``: ``(row, facet, s)`` per candidate.

    For a facet ``f`` with a vertex in common with ``facet[i]`` and facing the light, ``y = z - s w_t(f)``
    on the facet's plane with ``s > 0`` must fall inside the triangle (docs/physics.md §9.5 item 3).
    """
    m = z.shape[0]
    counts = np.zeros(m, dtype=np.int64)
    seen = np.empty(64, dtype=np.int64)
    for stage in range(2):
        if stage == 1:
            total = 0
            for i in range(m):
                total += counts[i]
            rows = np.empty(total, dtype=np.int64)
            facets = np.empty(total, dtype=np.int64)
            distances = np.empty(total)
            out = 0
        for i in range(m):
            f0 = facet[i]
            if f0 < 0:
                continue
            n_seen = 0
            for corner in range(3):
                v = triangles[f0, corner]
                for slot in range(facet_start[v], facet_start[v + 1]):
                    f = facet_list[slot]
                    duplicate = False
                    for j in range(n_seen):
                        if seen[j] == f:
                            duplicate = True
                            break
                    if duplicate or n_seen >= 64:
                        continue
                    seen[n_seen] = f
                    n_seen += 1
                    if not lit_side[f]:
                        continue
                    a = triangles[f, 0]
                    denom = (
                        w_t[f, 0] * face_normals[f, 0] + w_t[f, 1] * face_normals[f, 1] + w_t[f, 2] * face_normals[f, 2]
                    )
                    if denom >= 0.0:
                        continue
                    s = (
                        (z[i, 0] - points[a, 0]) * face_normals[f, 0]
                        + (z[i, 1] - points[a, 1]) * face_normals[f, 1]
                        + (z[i, 2] - points[a, 2]) * face_normals[f, 2]
                    ) / denom
                    if s <= 0.0:
                        continue
                    y0 = z[i, 0] - s * w_t[f, 0]
                    y1 = z[i, 1] - s * w_t[f, 1]
                    y2 = z[i, 2] - s * w_t[f, 2]
                    # inside the triangle: the three edge tests against the facet normal
                    inside = True
                    for e in range(3):
                        p = triangles[f, e]
                        q = triangles[f, (e + 1) % 3]
                        ex = points[q, 0] - points[p, 0]
                        ey = points[q, 1] - points[p, 1]
                        ez = points[q, 2] - points[p, 2]
                        rx = y0 - points[p, 0]
                        ry = y1 - points[p, 1]
                        rz = y2 - points[p, 2]
                        cx = ey * rz - ez * ry
                        cy = ez * rx - ex * rz
                        cz = ex * ry - ey * rx
                        if cx * face_normals[f, 0] + cy * face_normals[f, 1] + cz * face_normals[f, 2] < 0.0:
                            inside = False
                            break
                    if not inside:
                        continue
                    if stage == 0:
                        counts[i] += 1
                    else:
                        rows[out] = i
                        facets[out] = f
                        distances[out] = s
                        out += 1
    return rows, facets, distances


# --------------------------------------------------------------------------------------------------
# The walk
# --------------------------------------------------------------------------------------------------


class _Boundary:
    """The closed mesh: facets, outward facet normals, Embree scene, facets per vertex, distance bound."""

    def __init__(self, points, triangles, workers):
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int64)
        self.normals = triangle_normals(self.points, self.triangles)
        self.occluder = Occluder(self.points, self.triangles, workers=workers)
        self.eps = self.occluder.epsilon
        order = np.argsort(self.triangles.reshape(-1), kind="stable")
        self.facet_list = (order // 3).astype(np.int64)
        self.facet_start = np.zeros(len(self.points) + 1, dtype=np.int64)
        np.cumsum(np.bincount(self.triangles.reshape(-1), minlength=len(self.points)), out=self.facet_start[1:])
        edges, _ = unique_edges(self.triangles)
        self.longest_edge = float(np.linalg.norm(self.points[edges[:, 0]] - self.points[edges[:, 1]], axis=1).max())
        low, high = self.points.min(axis=0), self.points.max(axis=0)
        self.cell = max(float(np.max(high - low)) / DEPTH_GRID_CELLS, 1e-300)
        self.origin = low - self.cell
        self.dims = np.maximum(np.ceil((high - low) / self.cell).astype(np.int64) + 2, 1)
        self.depth = self.distance_bound(np.arange(len(self.points)))

    def distance_bound(self, vertices):
        """A grid of lower bounds of the distance to the facets around ``vertices``, mm.

        Every point of such a facet lies within the longest edge of one of its vertices, and every point of
        a cell within half the cell's diagonal of its centre.
        """
        axes = [self.origin[a] + (np.arange(self.dims[a]) + 0.5) * self.cell for a in range(3)]
        centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        if not len(vertices):
            return np.full(tuple(self.dims), np.inf)
        nearest, _ = cKDTree(self.points[vertices]).query(centres, workers=-1)
        bound = nearest - self.longest_edge - 0.5 * math.sqrt(3.0) * self.cell
        return np.maximum(bound, 0.0).reshape(tuple(self.dims))

    def lookup(self, grid, z):
        """Values of a :meth:`distance_bound` grid at points ``z`` (0 outside the grid)."""
        index = np.floor((z - self.origin) / self.cell).astype(np.int64)
        inside = np.all((index >= 0) & (index < self.dims), axis=1)
        out = np.zeros(len(z))
        i = index[inside]
        out[inside] = grid[i[:, 0], i[:, 1], i[:, 2]]
        return out


class _Light:
    """One directional light as the facets see it: refracted direction and beam flux density per facet."""

    def __init__(self, boundary: _Boundary, w_light, eta):
        cos_i = boundary.normals @ w_light
        self.w_light = w_light
        self.lit_side = cos_i > 1e-12
        c = np.clip(cos_i, 0.0, 1.0)
        self.w_t = refract(w_light, boundary.normals, eta)  # docs/physics.md §3.2
        cos_t = -np.einsum("ij,ij->i", self.w_t, boundary.normals)
        # flux density across the beam per unit irradiance: T12 cos_i / cos_t
        self.beam = np.where(self.lit_side, fresnel_transmittance(c, eta) * c / np.maximum(cos_t, 1e-300), 0.0)
        # how far every point is at least from the facets the light enters
        self.depth = boundary.distance_bound(np.unique(boundary.triangles[self.lit_side]))


def _hg(cos_theta, g):
    """Henyey-Greenstein phase function, 1/sr (docs/physics.md §9.1)."""
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * cos_theta) ** 1.5)


def _next_event(boundary: _Boundary, light: _Light, z, d, sigma_t, g, rng, stats):
    """Light arriving at interactions ``z`` (travelling along ``d``, in media ``sigma_t``, ``g``: one per
    interaction) straight from the entering beam, per unit weight (docs/physics.md §9.5)."""
    q = len(z)
    out = np.zeros(q)
    occ = boundary.occluder
    # Beyond NEE_FREE_OPTICAL_DEPTH from every lit facet the next event is taken with probability
    # exp(-(tau - NEE_FREE_OPTICAL_DEPTH)) and divided by it (unbiased; what it adds is at most exp(-tau)),
    # beyond NEE_MAX_OPTICAL_DEPTH never (docs/physics.md §9.5).
    tau = boundary.lookup(light.depth, z) * sigma_t
    chance = np.exp(-np.maximum(tau - NEE_FREE_OPTICAL_DEPTH, 0.0))
    near = np.flatnonzero((tau < NEE_MAX_OPTICAL_DEPTH) & (rng.random(q) < chance))
    stats["next_event_skipped"] += q - near.size
    if not near.size:
        return out
    zn = z[near]
    facet = occ.first_hits(zn, light.w_light).triangle
    searching = np.ones(near.size, dtype=bool)
    for _ in range(NEE_SEARCH_STEPS):
        rows = np.flatnonzero(searching & (facet >= 0))
        rows = rows[light.lit_side[facet[rows]]]
        if not rows.size:
            break
        found = occ.first_hits(zn[rows], -light.w_t[facet[rows]]).triangle
        same = found == facet[rows]
        searching[rows[same]] = False
        searching[rows[~same & (found < 0)]] = False
        keep = found >= 0
        facet[rows[keep]] = found[keep]
    rows, facets, s = _beam_candidates(
        zn,
        facet,
        boundary.points,
        boundary.triangles,
        boundary.normals,
        light.w_t,
        light.lit_side,
        boundary.facet_start,
        boundary.facet_list,
    )
    if not rows.size:
        return out
    first = occ.first_hits(zn[rows], -light.w_t[facets]).triangle
    clear = first == facets
    rows, facets, s = rows[clear], facets[clear], s[clear]
    entry = zn[rows] - s[:, None] * light.w_t[facets]
    lit = occ.visible(entry, boundary.normals[facets], light.w_light)
    rows, facets, s = rows[lit], facets[lit], s[lit]
    stats["entries_found"] += rows.size
    cos_scatter = -np.einsum("ij,ij->i", light.w_t[facets], d[near[rows]])
    at = near[rows]
    value = _hg(cos_scatter, g[at]) * light.beam[facets] * np.exp(-sigma_t[at] * s)
    out[near] = np.bincount(rows, weights=value, minlength=near.size) / chance[near]
    return out


class _Paths:
    """The paths in flight: position, direction, ray skip, weight, side, re-entered flag, estimates."""

    def __init__(self):
        self.sensor = np.empty(0, dtype=np.int64)
        self.channel = np.empty(0, dtype=np.int64)
        self.x = np.empty((0, 3))
        self.d = np.empty((0, 3))
        self.skip = np.empty(0)
        self.w = np.empty(0)
        self.inside = np.empty(0, dtype=bool)
        self.reentered = np.empty(0, dtype=bool)
        self.estimate = np.empty(0)
        self.estimate_reentered = np.empty(0)
        self.interactions = np.empty(0, dtype=np.int64)
        self.age = np.empty(0, dtype=np.int64)

    _FIELDS = (
        "sensor",
        "channel",
        "x",
        "d",
        "skip",
        "w",
        "inside",
        "reentered",
        "estimate",
        "estimate_reentered",
        "interactions",
        "age",
    )

    def add(self, sensor, channel, points, normals, eps, w0):
        """Start paths at the sensors given, in the channels given: on the surface point, along ``-n``
        (docs/physics.md §9.5 item 1)."""
        k = len(sensor)
        new = {
            "sensor": sensor,
            "channel": channel,
            "x": points[sensor],
            "d": -normals[sensor],
            "skip": np.full(k, eps),
            "w": np.full(k, w0),
            "inside": np.ones(k, dtype=bool),
            "reentered": np.zeros(k, dtype=bool),
            "estimate": np.zeros(k),
            "estimate_reentered": np.zeros(k),
            "interactions": np.zeros(k, dtype=np.int64),
            "age": np.zeros(k, dtype=np.int64),
        }
        for name in self._FIELDS:
            setattr(self, name, np.concatenate([getattr(self, name), new[name]]))

    def keep(self, rows):
        for name in self._FIELDS:
            setattr(self, name, getattr(self, name)[rows])


def _walk(boundary, light, start_points, start_normals, n_paths, coefficients, eta, rng, sums, stats, report):
    """Trace ``n_paths`` paths, path ``i`` for ``i % (sensors * n_channels)`` (``sensor * n_channels + channel``),
    keeping up to
    ``PATHS_PER_WAVE`` in flight; add each path's estimate, its square and its re-entered part to ``sums``
    (3, k, n_channels). ``coefficients`` holds ``sigma_t``, the albedo and ``g`` per channel (3, n_channels)."""
    n_channels = coefficients.shape[1]
    sigma_t, albedo, g = (np.ascontiguousarray(row) for row in coefficients)
    eps = boundary.eps
    w0 = float(fresnel_transmittance(1.0, 1.0 / eta)) / eta**2
    paths = _Paths()
    started = 0
    finished = 0
    work = WorkTally()
    flat = sums.reshape(3, -1)
    slots = sums.shape[1] * n_channels
    while started < n_paths or len(paths.sensor):
        if started < n_paths and len(paths.sensor) < PATHS_PER_WAVE // 2:
            take = (
                np.arange(started, min(n_paths, started + PATHS_PER_WAVE - len(paths.sensor)), dtype=np.int64) % slots
            )
            paths.add(take // n_channels, take % n_channels, start_points, start_normals, eps, w0)
            started += len(take)
        p = paths
        p.age += 1
        work.flights += len(p.sensor)
        xi = rng.random((2, len(p.sensor)))
        # a ray only where the flight may reach the boundary: deep inside, the flight is shorter than the
        # distance to any facet (docs/physics.md §9.5)
        hit = np.full(len(p.sensor), -1, dtype=np.int64)
        distance = np.full(len(p.sensor), np.inf)
        step = -np.log(xi[0]) / sigma_t[p.channel]
        cast = np.flatnonzero(~p.inside | (step >= boundary.lookup(boundary.depth, p.x)))
        stats["flights_without_ray"] += len(p.sensor) - cast.size
        hits = boundary.occluder.first_hits(p.x[cast] + p.skip[cast, None] * p.d[cast], p.d[cast])
        hit[cast], distance[cast] = hits.triangle, hits.distance
        distance[cast] += p.skip[cast]
        event = _flight(
            p.x, p.d, p.skip, p.w, p.inside, p.reentered, p.channel, hit, distance, xi[0], xi[1], boundary.normals,
            sigma_t, albedo, eta, eps,
        )  # fmt: skip
        scattered = np.flatnonzero(event == _SCATTER)
        stats["interactions"] += scattered.size
        p.interactions[scattered] += 1
        if scattered.size:
            c = p.channel[scattered]
            gained = p.w[scattered] * _next_event(
                boundary, light, p.x[scattered], p.d[scattered], sigma_t[c], g[c], rng, stats
            )
            p.estimate[scattered] += gained
            p.estimate_reentered[scattered] += np.where(p.reentered[scattered], gained, 0.0)
            xi = rng.random((2, scattered.size))
            _new_directions(p.d, scattered, p.channel, g, xi[0], xi[1])
        # Russian roulette on small weights
        low = np.flatnonzero(p.w < ROULETTE_FRACTION * w0)
        if low.size:
            survive = rng.random(low.size) < ROULETTE_SURVIVAL
            p.w[low[survive]] /= ROULETTE_SURVIVAL
            p.w[low[~survive]] = 0.0
        leaked = event == _LEAKED
        stopped = p.interactions >= MAX_INTERACTIONS
        stats["leaked_paths"] += int(np.count_nonzero(leaked))
        stats["stopped_paths"] += int(np.count_nonzero(stopped))
        done = leaked | stopped | (event == _ESCAPED) | (p.w == 0.0)
        if np.any(done):
            rows = np.flatnonzero(done)
            slot = p.sensor[rows] * n_channels + p.channel[rows]
            flat[0] += np.bincount(slot, weights=p.estimate[rows], minlength=flat.shape[1])
            flat[1] += np.bincount(slot, weights=p.estimate[rows] ** 2, minlength=flat.shape[1])
            flat[2] += np.bincount(slot, weights=p.estimate_reentered[rows], minlength=flat.shape[1])
            finished += rows.size
            work.add(p.age[rows])
            paths.keep(np.flatnonzero(~done))
            report(finished, work, paths.age)
    stats["paths"] += n_paths
    stats["rays"] = boundary.occluder.rays_cast


def _checked_mesh(points, triangles):
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles)
    if points.ndim != 2 or points.shape[1] != 3 or not len(points) or not np.all(np.isfinite(points)):
        raise MeshError("reference: points must be a finite (n, 3) array of mm with n > 0.")
    if (
        triangles.ndim != 2
        or triangles.shape[1] != 3
        or not len(triangles)
        or not np.issubdtype(triangles.dtype, np.integer)
    ):
        raise MeshError("reference: triangles must be a non-empty (m, 3) integer array.")
    if triangles.min() < 0 or triangles.max() >= len(points):
        raise MeshError(f"reference: triangle indices must lie in [0, {len(points) - 1}].")
    edges, edge_of_corner = unique_edges(triangles)
    open_edge = np.bincount(edge_of_corner.reshape(-1), minlength=len(edges)) == 1
    if open_edge.any():
        holes, largest = boundary_loops(edges[open_edge])
        # twice the largest: pymeshlab counts a hole's edges its own way, and a hole at the limit can stay open
        limit = max(2 * largest, 100)
        raise MeshError(
            f"reference: the mesh has {int(open_edge.sum())} edges with one triangle ({holes} "
            f"{'hole' if holes == 1 else 'holes'}, the largest of {largest} edges); the path tracer needs a closed "
            f"surface, so close them first: 'translucency inspect MESH --max-hole-edges {limit} -o closed.ply', "
            "then trace closed.ply."
        )
    if signed_volume(points, triangles) <= 0:
        raise MeshError("reference: the triangles face inward (negative enclosed volume); reverse their vertex order.")
    return points, triangles.astype(np.int64)


def _checked_sensors(sensor_points, sensor_normals):
    p = np.asarray(sensor_points, dtype=np.float64)
    n = np.asarray(sensor_normals, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or n.shape != p.shape or not np.all(np.isfinite(p)) or not np.all(np.isfinite(n)):
        raise InvalidParameterError(
            "reference: sensor points and normals must be finite (k, 3) arrays of the same shape."
        )
    length = np.linalg.norm(n, axis=1)
    if np.any(length < 0.5):
        raise InvalidParameterError("reference: every sensor normal must be a unit vector (some are zero or short).")
    return p, n / length[:, None]


def trace_radiance(
    points,
    triangles,
    sensor_points,
    sensor_normals,
    medium: Medium,
    light_direction,
    *,
    irradiance=1.0,
    spp: int = 64,
    seed: int = 0,
    workers: int | None = None,
    progress: Callable[[float, str], None] | None = None,
    time_limit: float | None = None,
) -> ReferenceRadiance:
    """Path-traced radiance along the normal at surface points of a closed mesh (docs/physics.md §9.5).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Vertex positions, mm.
    triangles : array_like of int, shape (m, 3)
        A closed, outward-oriented triangle mesh (every edge in two triangles).
    sensor_points, sensor_normals : array_like, shape (k, 3)
        Points on the surface (mm) and their unit outward normals; the radiance is estimated along each
        normal (for the vertices of the mesh: its points and vertex normals).
    medium : Medium
        Coefficients per channel (1/mm, unreduced ``sigma_s`` with the true ``g``) and ``eta``.
    light_direction : array_like, shape (3,)
        Direction toward the directional light (normalised here).
    irradiance : float or array_like, shape (C,)
        Irradiance of the light on a surface facing it, W/m² (per channel or one for all).
    spp : int
        Paths per sensor and channel (>= 2, for the standard error).
    seed : int
        Seed of the random numbers; the result depends on it, ``spp`` and the inputs only.
    workers : int, optional
        Threads for the Embree ray casts (default: every core this process may use).
    progress : callable, optional
        ``progress(fraction_done, message)`` every few seconds (the fraction of paths done, the time so far and
        the median relative standard error reached).
    time_limit : float, optional
        Seconds the tracing may take. Once :data:`CALIBRATION_SECONDS` of tracing have told the rate, a ``spp``
        whose paths would take longer is refused (:class:`~translucency.errors.BudgetError`, naming the ``spp``
        that fits), before the rest is traced.

    Returns
    -------
    ReferenceRadiance
        Radiance, standard error and the re-entered part per sensor and channel, W/(m² sr).
    """
    points, triangles = _checked_mesh(points, triangles)
    sensor_points, sensor_normals = _checked_sensors(sensor_points, sensor_normals)
    w_light = np.asarray(light_direction, dtype=np.float64).reshape(-1)
    if w_light.shape != (3,) or not np.all(np.isfinite(w_light)) or not np.linalg.norm(w_light) > 0:
        raise InvalidParameterError("reference: light_direction must be a finite, non-zero 3-vector.")
    w_light = w_light / np.linalg.norm(w_light)
    spp = check_spp(spp)
    seed = check_seed(seed)
    check_limits(None, time_limit)
    n_channels = medium.n_channels
    E = np.broadcast_to(np.asarray(irradiance, dtype=np.float64), (n_channels,))
    if not np.all(np.isfinite(E)) or np.any(E < 0):
        raise InvalidParameterError("reference: irradiance must be finite and not negative (W/m²).")

    started = time.perf_counter()
    boundary = _Boundary(points, triangles, workers)
    eta = float(medium.eta)
    light = _Light(boundary, w_light, eta)
    k = len(sensor_points)
    stats = {
        "paths": 0,
        "interactions": 0,
        "rays": 0,
        "leaked_paths": 0,
        "stopped_paths": 0,
        "next_event_skipped": 0,
        "flights_without_ray": 0,
        "entries_found": 0,
    }
    table = np.stack([medium.sigma_a, medium.sigma_s, medium.g], axis=1)
    distinct, channel_of = np.unique(table, axis=0, return_inverse=True)
    channel_of = channel_of.reshape(-1)
    # round robin: every (sensor, channel) gets its n-th path before any gets its (n+1)-th, so the running
    # error is the same everywhere and the progress line can tell the time to a given noise; the channels
    # walk together, so the few long paths at the end are waited for once
    n_distinct = len(distinct)
    n_paths = spp * k * n_distinct  # path i is for slot i % (k * n_distinct): the queue is never held
    results = np.zeros((3, k, n_distinct))
    coefficients = np.stack(
        [distinct[:, 0] + distinct[:, 1], distinct[:, 1] / (distinct[:, 0] + distinct[:, 1]), distinct[:, 2]]
    )
    rng = np.random.default_rng(seed)
    last = [time.perf_counter()]

    def report(finished, work, ages):
        now = time.perf_counter()
        calibrated = time_limit is not None and CALIBRATION_SECONDS <= now - started and finished < n_paths
        shown = progress is not None and (now - last[0] >= PROGRESS_SECONDS or finished >= n_paths)
        if calibrated:
            check_time(time_limit, now - started, work.share(finished, n_paths, ages, largest=True), spp)
        done = work.share(finished, n_paths, ages) if shown else 0.0
        if not shown:
            return
        last[0] = now
        samples = finished // (k * n_distinct)
        error = _median_relative_error(*_mean_and_stderr(results, samples)) if samples >= 2 else math.inf
        progress(done, progress_line(done, now - started, samples, error))

    _walk(boundary, light, sensor_points, sensor_normals, n_paths, coefficients, eta, rng, results, stats, report)
    mean, stderr = _mean_and_stderr(results, spp)
    reentered = results[2] / spp
    return ReferenceRadiance(
        radiance=mean[:, channel_of] * E,
        radiance_stderr=stderr[:, channel_of] * E,
        radiance_reentered=reentered[:, channel_of] * E,
        spp=int(spp),
        seconds=time.perf_counter() - started,
        stats=stats,
    )
