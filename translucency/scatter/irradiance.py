"""Incident light per source vertex: flux density, flux and flux-weighted refracted direction.

For every vertex ``i`` and every light sample ``k`` (a directional light, one environment sample, or
a point light) with ``c_ik = n_i . w_ik > 0`` and the way to the light free (``V_ik``), light enters
the medium with flux density ``T12(c_ik) E_k c_ik`` along the refracted direction ``w12_ik``
(docs/physics.md §3.2, §5.1, §7.2). :func:`incident_flux` sums the samples per vertex:

* ``phi_i = sum_k T12 E_k c_ik V_ik`` (flux density) and ``Phi_i = A_i phi_i`` (flux);
* ``w12_mean_i = sum_k |phi_ik| w12_ik / sum_k |phi_ik|`` with ``|.|`` the channel sum, and its
  direction ``w12_i`` (unit).

For one directional light this is exact. For several, the solver's ``B(x_o) = sum_i S_d(x_i, w12_i;
x_o) Phi_i`` becomes an approximation: the virtual-source term of ``S_d`` is affine in the source
direction (its distance ``d_v`` does not depend on it), so feeding it ``w12_mean`` reproduces the
per-sample sum exactly (channel by channel when all lights share one colour, before the clamp at 0);
the real-source term is not (``d_r`` depends on the direction), so the unit ``w12`` is an
approximation there. ``per_direction=True`` keeps every sample's contribution
(:class:`LightContribution`) for per-direction summation; ``bench/aggregation.py`` measures the
difference on a mesh with the reference dipole.

Units: with ``E`` in W/m² and areas in mm², ``phi`` is in W/m² and ``Phi`` in W mm²/m² (= 1e-6 W);
``S_d`` (1/(mm² sr)) times ``Phi`` is then in W/(m² sr) (see :mod:`translucency.scatter.lights`).

Visibility is optional (``occluder`` or ``triangles``); with a
:class:`~translucency.scatter.visibility.VisibilityCache` the Embree scene and every sample's
visibility are kept, keyed by mesh, ray origins and light geometry, so a material change (only
``eta`` and the coefficients differ) traces no ray again.

========== ============================================================== ============
symbol     meaning                                                        unit
========== ============================================================== ============
x_i, n_i   source vertex and its outward unit normal                      mm, 1
A_i        vertex area (a third of the adjacent triangle areas)           mm²
w_ik       unit vector from x_i toward light sample k                     1
c_ik       n_i . w_ik, cosine of incidence                                1
E_k        irradiance of sample k on a surface facing it                  W/m²
T12        Fresnel transmittance at entry, 1 - F_r(c, eta)                1
V_ik       visibility (1: unobstructed, 0: shadowed)                      1
phi_i      flux density entering the medium                               W/m²
Phi_i      flux entering the medium, A_i phi_i                            W mm²/m²
w12_ik     refracted direction of sample k (into the medium)              1
w12_mean   flux-weighted mean of the w12_ik (length <= 1)                 1
w12        w12_mean normalised                                            1
eta        relative index of refraction n_inside / n_outside              1
========== ============================================================== ============
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numba
import numpy as np

from ..errors import InvalidParameterError, warn_user
from ..geometry.measure import row_lengths
from ..geometry.topology import kernel_array
from .fresnel import fresnel_reflectance_scalar, refracted
from .lights import POINT_LIGHT_MIN_DISTANCE_MM, PointLight, as_light_list, point_light_irradiance
from .visibility import Occluder, VisibilityCache, array_digest

__all__ = [
    "IncidentLight",
    "IncidentStats",
    "LightContribution",
    "carried_light",
    "incident_flux",
]


@dataclass
class IncidentStats:
    """What :func:`incident_flux` did and skipped.

    Attributes
    ----------
    n_vertices, n_samples : int
        Source vertices; light samples (a directional or point light is one, an environment N).
    n_lit : int
        Vertices receiving any flux.
    n_backfacing : int
        Vertex-sample pairs skipped without a ray because ``n . w <= 0``.
    n_degenerate_normals : int
        Vertices with a zero-length normal (they receive no light).
    n_rays, n_shadowed : int
        Shadow rays traced now, and pairs found shadowed (traced now or reused).
    n_visibility_reused : int
        Samples whose visibility came from the cache (no ray traced).
    scene : str
        ``"off"`` (no visibility), ``"given"``, ``"built"`` or ``"reused"`` (Embree scene).
    n_distance_clamped : int
        Point-light distances raised to ``POINT_LIGHT_MIN_DISTANCE_MM``.
    seconds : dict
        Wall time of ``scene`` (build), ``visibility``, ``flux`` and ``total``.
    """

    n_vertices: int = 0
    n_samples: int = 0
    n_lit: int = 0
    n_backfacing: int = 0
    n_degenerate_normals: int = 0
    n_rays: int = 0
    n_shadowed: int = 0
    n_visibility_reused: int = 0
    scene: str = "off"
    n_distance_clamped: int = 0
    seconds: dict = field(default_factory=lambda: {"scene": 0.0, "visibility": 0.0, "flux": 0.0, "total": 0.0})

    def as_dict(self) -> dict:
        """Plain dictionary (for reports and metadata)."""
        return asdict(self)


@dataclass(frozen=True, eq=False)
class LightContribution:
    """The light one sample brings to the vertices it reaches (per-direction summation).

    Attributes
    ----------
    light : int
        Index of the light (in the ``lights`` given to :func:`incident_flux`) the sample belongs to.
    direction : ndarray, shape (3,) or None
        Direction toward the sample (None for a point light, whose direction varies per vertex).
    vertices : ndarray of int, shape (k,)
        Vertices the sample reaches (front-facing and unshadowed).
    phi_rgb, flux_rgb : ndarray, shape (k, 3)
        Flux density (W/m²) and flux (W mm²/m²) entering at those vertices.
    w12 : ndarray, shape (k, 3)
        Unit refracted direction of the sample at those vertices.
    """

    light: int
    direction: np.ndarray | None
    vertices: np.ndarray
    phi_rgb: np.ndarray
    flux_rgb: np.ndarray
    w12: np.ndarray


@dataclass(frozen=True, eq=False)
class IncidentLight:
    """Light entering the medium at each source vertex (the solver's sources).

    Attributes
    ----------
    phi_rgb : ndarray, shape (n, 3)
        Flux density ``phi_i = sum_k T12 E_k c_ik V_ik``, W/m² (defined also where the area is 0).
    flux_rgb : ndarray, shape (n, 3)
        Flux ``Phi_i = A_i phi_i``, W mm²/m².
    w12 : ndarray, shape (n, 3)
        Unit flux-weighted refracted direction; ``-n_i`` where no light enters.
    w12_mean : ndarray, shape (n, 3)
        Flux-weighted mean of the unit refracted directions (length <= 1, 1 for a single light);
        the exact direction argument of the virtual-source term (module docstring).
    lights : tuple
        The lights, as given.
    stats : IncidentStats
    contributions : tuple of LightContribution or None
        Per-sample contributions, when asked for with ``per_direction=True``.
    """

    phi_rgb: np.ndarray
    flux_rgb: np.ndarray
    w12: np.ndarray
    w12_mean: np.ndarray
    lights: tuple
    stats: IncidentStats
    contributions: tuple | None = None


def _validated_arrays(points, normals, areas):
    """``(points, unit normals, areas, degenerate normals, normals as given)`` as float64 arrays, checked; the normals
    as given key the visibility cache (a Scene's are read-only and hashed once, :func:`~.visibility.array_digest`)."""
    try:
        points = np.asarray(points, dtype=np.float64)
        normals = np.asarray(normals, dtype=np.float64)
        areas = np.asarray(areas, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError("incident_flux: points, normals and areas must be numeric arrays.") from None
    if points.ndim != 2 or points.shape[1] != 3:
        raise InvalidParameterError(f"incident_flux: points must have shape (n, 3), got {points.shape}.")
    n = len(points)
    if normals.shape != (n, 3):
        raise InvalidParameterError(
            f"incident_flux: normals must have shape ({n}, 3) like points, got {normals.shape}."
        )
    if areas.shape != (n,):
        raise InvalidParameterError(f"incident_flux: areas must have shape ({n},), one per vertex, got {areas.shape}.")
    for name, value in (("points", points), ("normals", normals), ("areas", areas)):
        if not np.all(np.isfinite(value)):
            raise InvalidParameterError(f"incident_flux: {name} contain NaN or infinite values; clean the mesh first.")
    if np.any(areas < 0):
        raise InvalidParameterError(
            f"incident_flux: vertex areas must be >= 0 (mm²), got a minimum of {areas.min():g}."
        )
    length = row_lengths(normals)
    degenerate = ~(length > 1e-12)
    given = normals
    normals = normals / np.where(degenerate, 1.0, length)[:, None]
    normals[degenerate] = 0.0
    return points, normals, areas, degenerate, given


def _validated_eta(eta) -> float:
    if np.ndim(eta) != 0:
        raise InvalidParameterError(f"incident_flux: eta must be a single number, got {eta!r}.")
    eta = float(eta)
    if not (np.isfinite(eta) and eta >= 1.0):
        raise InvalidParameterError(
            f"incident_flux: eta = n_inside / n_outside must be a finite number >= 1, got {eta!r}."
        )
    return eta


def _samples(lights):
    """Expand lights into samples ``(light index, kind, vector, rgb)``; kind is 'dir' or 'point'."""
    out = []
    for index, light in enumerate(lights):
        if isinstance(light, PointLight):
            out.append((index, "point", light.position_mm, light.intensity_rgb))
        else:
            samples = light.directional_samples()
            out.extend((index, "dir", w, e) for w, e in zip(samples.directions, samples.irradiance_rgb))
    return out


RAYS_PER_BATCH = 1 << 18
"""Shadow rays of several samples are traced together up to this many (one threaded Embree call)."""


@dataclass
class _Job:
    """One light sample at the vertices facing it: indices, cosines, directions, distances."""

    light: int
    kind: str  # "dir" or "point"
    vector: np.ndarray  # direction toward the light, or the point light's position (mm)
    rgb: np.ndarray  # E (W/m²) or I (W/sr)
    front: np.ndarray  # vertices with n . w > 0
    cos: np.ndarray  # n . w at those vertices
    w: np.ndarray  # (3,) for a direction, (k, 3) per vertex for a point light
    distance: np.ndarray | None  # mm, point lights only


def _job(sample, points, normals) -> _Job:
    light, kind, vector, rgb = sample
    if kind == "dir":
        cos = normals @ vector
        front = np.flatnonzero(cos > 0.0)
        return _Job(light, kind, vector, rgb, front, cos[front], vector, None)
    to_light = vector[None, :] - points
    distance = np.linalg.norm(to_light, axis=1)
    w = to_light / np.where(distance > 0.0, distance, 1.0)[:, None]
    cos = np.einsum("ij,ij->i", normals, w)
    front = np.flatnonzero((cos > 0.0) & (distance > 0.0))
    return _Job(light, kind, vector, rgb, front, cos[front], w[front], distance[front])


def warn_near_point_lights(lights, points, areas) -> None:
    """A :class:`~translucency.errors.TranslucencyWarning` for each point light nearer to a vertex than the
    mesh's vertex spacing (the square root of the median vertex area, mm): the irradiance ``I / d^2`` of its
    nearest vertices is then set by where the light sits between them, not by the surface, and ``B`` there means
    little (a light on the surface gives any value up to ``I / (1 um)^2``)."""
    if not len(points):
        return
    spacing = float(np.sqrt(np.median(areas)))
    for light in lights:
        if not isinstance(light, PointLight):
            continue
        nearest = float(np.min(np.linalg.norm(points - light.position_mm[None, :], axis=1)))
        if nearest < spacing:
            warn_user(
                f"a point light at {', '.join(f'{v:.4g}' for v in light.position_mm)} mm is {nearest:.2g} mm from "
                f"the surface, nearer than its vertex spacing ({spacing:.2g} mm): its irradiance (1/d^2) at the "
                f"nearest vertices says little about the surface; move it at least {spacing:.2g} mm away."
            )


def _irradiance(job, stats) -> np.ndarray:
    """Irradiance (W/m², k x 3) of a job's sample on a surface facing it, at its vertices (one row for all of them
    for a direction)."""
    if job.kind == "dir":
        return np.asarray(job.rgb, dtype=np.float64).reshape(1, 3)
    stats.n_distance_clamped += int(np.count_nonzero(job.distance < POINT_LIGHT_MIN_DISTANCE_MM))
    return point_light_irradiance(job.rgb, job.distance)  # inverse square, E = I / d_m^2


def _batches(samples, points, normals, stats):
    """Jobs grouped so that each group casts about RAYS_PER_BATCH rays at most (one big sample alone)."""
    batch, rays = [], 0
    for sample in samples:
        job = _job(sample, points, normals)
        stats.n_backfacing += len(points) - len(job.front)
        if batch and rays + len(job.front) > RAYS_PER_BATCH:
            yield batch
            batch, rays = [], 0
        batch.append(job)
        rays += len(job.front)
    if batch:
        yield batch


def _apply_visibility(batch, occluder, cache, origins_key, points, normals, stats):
    """Drop the shadowed vertices from each job: cached visibility, or one Embree call for the rest."""
    keys = [(occluder.key, origins_key, job.kind, tuple(np.round(job.vector, 12))) for job in batch]
    visible = [cache.get(key) if cache is not None else None for key in keys]
    todo = [i for i, v in enumerate(visible) if v is None and len(batch[i].front)]
    stats.n_visibility_reused += sum(1 for v in visible if v is not None)
    if todo:
        jobs = [batch[i] for i in todo]
        front = np.concatenate([job.front for job in jobs])
        directions = np.concatenate([np.broadcast_to(job.w, (len(job.front), 3)) for job in jobs])
        distances = np.concatenate(
            [job.distance if job.distance is not None else np.full(len(job.front), np.inf) for job in jobs]
        )
        traced = occluder.visible(points[front], normals[front], directions, distances)
        for i, part in zip(todo, np.split(traced, np.cumsum([len(job.front) for job in jobs])[:-1])):
            visible[i] = part
            if cache is not None:
                cache.put(keys[i], part)
    for job, v in zip(batch, visible):
        if v is None:  # no vertex faces this sample
            continue
        stats.n_shadowed += int(len(job.front) - np.count_nonzero(v))
        job.front, job.cos = job.front[v], job.cos[v]
        if job.kind == "point":
            job.w, job.distance = job.w[v], job.distance[v]


def incident_flux(
    points,
    normals,
    areas,
    lights,
    eta,
    *,
    triangles=None,
    occluder=None,
    cache: VisibilityCache | None = None,
    per_direction: bool = False,
) -> IncidentLight:
    """Flux and flux-weighted refracted direction entering the medium at each source vertex.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Source vertices, mm.
    normals : array_like, shape (n, 3)
        Outward vertex normals (normalised here; a zero normal receives no light).
    areas : array_like, shape (n,)
        Vertex areas, mm².
    lights : light or sequence of lights
        :class:`~translucency.scatter.lights.DirectionalLight`, ``PointLight`` or
        ``EnvironmentLight`` objects; their contributions add.
    eta : float
        Relative index of refraction ``n_inside / n_outside`` (>= 1).
    triangles : array_like, shape (m, 3), optional
        Mesh triangles over ``points``: cast shadow rays against this mesh (scene from ``cache``
        when given). Without ``triangles`` and ``occluder`` every front-facing vertex is lit.
    occluder : Occluder, optional
        A ready Embree scene to cast shadow rays against (takes precedence over ``triangles``).
    cache : VisibilityCache, optional
        Reuse scenes and visibility from earlier calls (and store this call's).
    per_direction : bool, optional
        Also return every sample's contribution (``contributions``), for per-direction summation.
        Memory grows with the number of samples (per sample and vertex it reaches: an index and three rows of
        3 float64, :class:`LightContribution`).

    Returns
    -------
    IncidentLight
    """
    t_start = time.perf_counter()
    points, normals, areas, degenerate, given_normals = _validated_arrays(points, normals, areas)
    eta = _validated_eta(eta)
    lights = as_light_list(lights)
    warn_near_point_lights(lights, points, areas)
    n = len(points)
    stats = IncidentStats(n_vertices=n, n_degenerate_normals=int(degenerate.sum()))

    t = time.perf_counter()
    if occluder is not None:
        if not isinstance(occluder, Occluder):
            raise InvalidParameterError(f"incident_flux: occluder must be an Occluder, got {type(occluder).__name__}.")
        stats.scene = "given"
    elif triangles is not None:
        if cache is not None:
            occluder, reused = cache.occluder(points, triangles)
            stats.scene = "reused" if reused else "built"
        else:
            occluder = Occluder(points, triangles)
            stats.scene = "built"
    stats.seconds["scene"] = time.perf_counter() - t
    origins_key = array_digest(points, given_normals) if (cache is not None and occluder is not None) else None

    phi = np.zeros((n, 3))
    weighted_w12 = np.zeros((n, 3))
    contributions = [] if per_direction else None
    rays_before = occluder.rays_cast if occluder is not None else 0
    seconds_visibility = 0.0
    samples = _samples(lights)
    stats.n_samples = len(samples)
    for batch in _batches(samples, points, normals, stats):
        t = time.perf_counter()
        if occluder is not None:
            _apply_visibility(batch, occluder, cache, origins_key, points, normals, stats)
        seconds_visibility += time.perf_counter() - t
        for job in batch:  # a sample's vertices are distinct: each adds once to a vertex's sums
            rows = (job.front, job.cos, np.atleast_2d(job.w), _irradiance(job, stats), normals)
            keep = contributions is not None
            p, w12_k = (np.empty((job.front.size if keep else 0, 3)) for _ in range(2))
            inputs = (kernel_array(a, dt) for a, dt in zip(rows, (np.int64, *(np.float64,) * 4), strict=True))
            _entering(*inputs, float(eta), phi, weighted_w12, p, w12_k)
            if keep:
                f = job.front
                direction = job.vector.copy() if job.kind == "dir" else None
                contributions.append(LightContribution(job.light, direction, f, p, areas[f, None] * p, w12_k))

    w12_mean, w12, lit = _mean_direction(weighted_w12, phi.sum(axis=1), normals)
    flux = areas[:, None] * phi

    stats.n_lit = int(np.count_nonzero(lit))
    stats.n_rays = (occluder.rays_cast - rays_before) if occluder is not None else 0
    stats.seconds["visibility"] = seconds_visibility
    stats.seconds["total"] = time.perf_counter() - t_start
    stats.seconds["flux"] = stats.seconds["total"] - seconds_visibility - stats.seconds["scene"]
    return IncidentLight(
        phi_rgb=phi,
        flux_rgb=flux,
        w12=w12,
        w12_mean=w12_mean,
        lights=lights,
        stats=stats,
        contributions=tuple(contributions) if contributions is not None else None,
    )


@numba.njit(cache=True, nogil=True)
def _entering(front, cos, w, irradiance, normals, eta, phi, weighted, pairs_phi, pairs_w12):
    """One light sample's light into the vertices ``front`` facing it (cosines ``cos``): the flux density ``T12 E
    cos(theta)`` (docs/physics.md §3.1, §5.1) added to their rows of ``phi (n, 3)``, and the refracted direction
    ``w12`` (§3.2) weighted by its sum over the channels to ``weighted``. ``w`` (unit, toward the light) and
    ``irradiance`` (W/m²) have a row per vertex or one for all; each pair's flux density and ``w12`` also go to
    ``pairs_phi`` and ``pairs_w12`` where they have rows."""
    w_step = 1 if w.shape[0] == front.shape[0] and w.shape[0] > 1 else 0
    e_step = 1 if irradiance.shape[0] == front.shape[0] and irradiance.shape[0] > 1 else 0
    keep = pairs_phi.shape[0] > 0
    for q in range(front.shape[0]):
        v = front[q]
        c = cos[q]
        t = (1.0 - fresnel_reflectance_scalar(c, eta)) * c
        e = irradiance[q * e_step]
        p0, p1, p2 = t * e[0], t * e[1], t * e[2]
        d = w[q * w_step]
        w0, w1, w2 = refracted(d[0], d[1], d[2], normals[v, 0], normals[v, 1], normals[v, 2], eta)
        phi[v, 0] += p0
        phi[v, 1] += p1
        phi[v, 2] += p2
        total = p0 + p1 + p2
        weighted[v, 0] += total * w0
        weighted[v, 1] += total * w1
        weighted[v, 2] += total * w2
        if keep:
            pairs_phi[q, 0], pairs_phi[q, 1], pairs_phi[q, 2] = p0, p1, p2
            pairs_w12[q, 0], pairs_w12[q, 1], pairs_w12[q, 2] = w0, w1, w2


def _mean_direction(weighted, weight, normals):
    """``(w12_mean, w12, lit)``: the flux-weighted mean refracted direction ``weighted / weight`` (n, 3) where any
    flux enters (``lit``; every ``w12`` there points into the medium, so the mean never vanishes), the inward normal
    elsewhere (any inward unit vector will do), ``(0, 0, -1)`` where that normal is 0 too; and its unit vector."""
    lit = weight > 0.0
    w12_mean, w12 = np.empty_like(weighted), np.empty_like(weighted)
    _mean_directions(*(kernel_array(a, np.float64) for a in (weighted, weight, normals)), w12_mean, w12)
    return w12_mean, w12, lit


@numba.njit(cache=True, nogil=True)
def _mean_directions(weighted, weight, normals, mean, unit):
    """:func:`_mean_direction`'s mean and unit directions into ``mean`` and ``unit``, a vertex at a time."""
    for v in range(weighted.shape[0]):
        for k in range(3):
            mean[v, k] = weighted[v, k] / weight[v] if weight[v] > 0.0 else -normals[v, k]
        length = math.sqrt(mean[v, 0] * mean[v, 0] + mean[v, 1] * mean[v, 1] + mean[v, 2] * mean[v, 2])
        if length == 0.0:  # a degenerate normal where no light arrives
            mean[v, 0], mean[v, 1], mean[v, 2] = 0.0, 0.0, -1.0
            length = 1.0
        for k in range(3):
            unit[v, k] = mean[v, k] / length


def carried_light(light: IncidentLight, gather, normals, areas) -> IncidentLight:
    """The light entering a fine mesh carried onto the vertices of a coarser one that stands for it (a proxy),
    the flux kept (docs/physics.md §8.6).

    Parameters
    ----------
    light : IncidentLight
        The light traced at every vertex of the fine mesh (its own normals, shadows and relief).
    gather : callable
        ``gather(values)``: per-vertex amounts of the fine mesh, shape ``(n_fine, k)``, summed onto the coarse
        vertices, shape ``(n, k)``, each fine vertex sharing its amount among a few coarse vertices with weights
        that sum to 1 (:meth:`translucency.io.decimate.ProxyMapping.gather`).
    normals : array_like, shape (n, 3)
        The coarse mesh's outward unit vertex normals (the direction given where no light arrives).
    areas : array_like, shape (n,)
        The coarse mesh's vertex areas, mm².

    Returns
    -------
    IncidentLight
        On the coarse vertices ``j``: the flux ``Phi_j = sum_i w_ij Phi_i`` (W mm²/m²; the total entering is
        the fine mesh's), the flux density ``phi_j = Phi_j / A_j`` (W/m²) and the flux-weighted mean refracted
        direction ``w12_mean_j = sum_i w_ij |Phi_i| w12_mean_i / sum_i w_ij |Phi_i|`` (``|.|`` the channel sum);
        the per-sample contributions carried the same way. ``stats`` are the fine mesh's (what was traced).
    """
    normals = np.asarray(normals, dtype=np.float64)
    areas = np.asarray(areas, dtype=np.float64)

    def carried(flux_rgb, w12_mean):
        flux = gather(flux_rgb)
        fine_weight = flux_rgb.sum(axis=1)
        w12_mean_out, w12, lit = _mean_direction(gather(fine_weight[:, None] * w12_mean), gather(fine_weight), normals)
        phi = np.divide(flux, areas[:, None], out=np.zeros_like(flux), where=areas[:, None] > 0.0)
        return phi, flux, w12, w12_mean_out, lit

    phi, flux, w12, w12_mean, _ = carried(light.flux_rgb, light.w12_mean)
    contributions = None
    if light.contributions is not None:
        n_fine = len(light.flux_rgb)
        contributions = []
        for part in light.contributions:
            fine_flux = np.zeros((n_fine, 3))
            fine_w12 = np.zeros((n_fine, 3))
            fine_flux[part.vertices] = part.flux_rgb
            fine_w12[part.vertices] = part.w12
            part_phi, part_flux, part_w12, _, reached = carried(fine_flux, fine_w12)
            vertices = np.flatnonzero(reached)
            contributions.append(
                LightContribution(
                    part.light, part.direction, vertices, part_phi[vertices], part_flux[vertices], part_w12[vertices]
                )
            )
        contributions = tuple(contributions)
    return IncidentLight(
        phi_rgb=phi,
        flux_rgb=flux,
        w12=w12,
        w12_mean=w12_mean,
        lights=light.lights,
        stats=light.stats,
        contributions=contributions,
    )


#: The compiled kernels of the light that enters (with :data:`translucency.scatter.fresnel.FRESNEL_KERNELS`): numba
#: compiles each on first use; the set-up compiles them ahead (:mod:`translucency.app.warmup`).
LIGHT_KERNELS = (_entering, _mean_directions)
