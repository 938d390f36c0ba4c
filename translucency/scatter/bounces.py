"""Light that leaves the surface and enters it again: the bounce gather and the extra solves.

The solver's ``B`` (docs/physics.md §5.3) is the light that entered once. Light leaving the surface
-- the subsurface exitance ``L = T21 B`` and the boundary's mirror reflection of the lights -- partly
reaches the surface again (ears, folds, concavities) and enters there. This module turns that light
into the solver's input (a flux density ``phi`` and a refracted direction ``w12`` per vertex, as
:mod:`translucency.scatter.irradiance` does for the lights) and solves again, ``bounces`` times
(docs/physics.md §7.4):

* :func:`gather_exitance` -- ``phi_p = (pi / K) sum_k T12(n_p . w_k) T21(n_h . -w_k) B(h_k)`` over ``K``
  cosine-weighted directions ``w_k`` of the outer hemisphere of every vertex ``p`` (stratified, turned
  per vertex), ``h_k`` the first point of the mesh the ray meets (Embree), ``B`` and ``n`` interpolated
  there; rays that escape or meet a back face bring nothing;
* :func:`specular_reflection` -- the mirror reflection ``F_r E cos V A_q`` of the lights at every lit
  vertex ``q``, one ray per vertex (one light sample drawn per vertex in proportion to its reflected
  flux), deposited on the triangle it meets by barycentric weight and entering with ``T12``;
* :func:`solve_bounces` -- ``B_1 = solve(gather(B_0) + specular)``, ``B_{k+1} = solve(gather(B_k))``;
  the result is ``B_1 + ... + B_N``, to be added to ``B_0``.

Everything is linear in ``B`` and deterministic (a fixed seed): the same call gives the same answer.

========== ============================================================== ===============
symbol     meaning                                                        unit
========== ============================================================== ===============
B          diffuse radiance factor per vertex and channel                 W/(m² sr)
K          rays per vertex of the gather (:data:`GATHER_RAYS`)            1
w_k        unit direction of ray k, outward (n_p . w_k > 0)               1
T12, T21   Fresnel transmittance at entry and at exit (outside cosine)    1
F_r        Fresnel reflectance of the lights at the boundary              1
phi        flux density that crosses the boundary inward                  W/m²
w12        unit flux-weighted refracted direction (into the medium)       1
A          vertex area (a third of the adjacent triangle areas)           mm²
========== ============================================================== ===============
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .fresnel import fresnel_reflectance, fresnel_transmittance, refract
from .lights import GOLDEN_RATIO, PointLight, as_light_list, point_light_irradiance
from .names import DEFAULT_DEVICE, check_bounces
from .surface import PerSurface
from .visibility import Occluder

__all__ = [
    "GATHER_RAYS",
    "Bounces",
    "GatherPaths",
    "gather_paths",
    "ReenteringLight",
    "cosine_directions",
    "gather_exitance",
    "reentering_light",
    "solve_bounces",
    "specular_reflection",
]

#: Rays per vertex of the gather (docs/physics.md §7.4). The solver spreads the gathered flux over many
#: vertices, so most of the per-vertex noise averages out in ``B``; it stays large only in the darkest
#: concavities, where few rays see the lit side. The noise falls as 1/sqrt(rays) and the gather's time grows
#: with them (bench/README.md, "Bounces").
GATHER_RAYS = 32
#: The bounce solves of ``cutoff`` and ``tree`` run at this many times the user's tolerance (at most
#: :data:`MAX_BOUNCE_TOL`): the re-entered part is a share of ``B``, so its error counts for less in the total,
#: and a looser bounce solve is much cheaper (bench/README.md, "Bounces").
BOUNCE_TOL_FACTOR = 10.0
#: The bounce solves' tolerance is at most this (and at least the user's).
MAX_BOUNCE_TOL = 0.5
#: Rays traced per Embree call (vertices are taken in blocks of this many rays).
RAYS_PER_BLOCK = 1 << 18
#: Seed of the per-vertex rotations and draws (the answer is deterministic).
SEED = 20240615


@dataclass(frozen=True, eq=False)
class ReenteringLight:
    """Light that left the surface and enters it again, as the solver's input.

    Attributes
    ----------
    phi_rgb : ndarray, shape (n, C)
        Flux density crossing the boundary inward, W/m² per W/m² of the lights.
    w12 : ndarray, shape (n, 3)
        Unit flux-weighted refracted direction; ``-n`` where nothing enters.
    stats : dict
        Rays traced, hits, back faces, escapes, and seconds (``gather``, ``specular``).
    """

    phi_rgb: np.ndarray
    w12: np.ndarray
    stats: dict


@dataclass
class Bounces:
    """What :func:`solve_bounces` returns.

    Attributes
    ----------
    B : ndarray, shape (n, C)
        The light that re-entered, ``B_1 + ... + B_N`` (add it to the first solve's ``B``), W/(m² sr).
    orders : list of ndarray
        Each ``B_k`` on its own.
    stats : dict
        ``bounces`` done, ``rays_per_vertex``, ``rays``, the bounce solves' ``tol``, ``entered_flux`` (per
        order and channel, W mm²/m²), ``mirror`` (the lights' ``reflected_flux`` and the ``deposited_flux``
        that enters again), ``seconds`` of ``gather``, ``specular`` and ``solve``.
    solutions : list
        The solver's :class:`~translucency.scatter.solve.Solution` of each bounce.
    """

    B: np.ndarray
    orders: list
    stats: dict
    solutions: list = field(default_factory=list)


def _frames(normals):
    """Two unit tangents completing each unit normal to a right-handed frame (Duff et al. 2017)."""
    x, y, z = normals[:, 0], normals[:, 1], normals[:, 2]
    sign = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    t1 = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=1)
    t2 = np.stack([b, sign + y * y * a, -y], axis=1)
    return t1, t2


def cosine_directions(normals, rays: int, offsets) -> np.ndarray:
    """``rays`` cosine-weighted unit directions over the outer hemisphere of each normal (pdf cos/pi).

    A Fibonacci lattice of ``rays`` points in the unit square (one in each of ``rays`` strata along
    the first axis), shifted modulo 1 by each vertex's ``offsets`` (a Cranley-Patterson rotation: every
    direction is then uniformly distributed, so the estimate is unbiased), mapped to the disk
    ``r = sqrt(u1), phi = 2 pi u2`` and lifted to the hemisphere (Malley's method).

    Parameters
    ----------
    normals : ndarray, shape (n, 3)
        Unit normals.
    rays : int
        Directions per normal.
    offsets : ndarray, shape (n, 2)
        Shifts in [0, 1)^2, one per normal.

    Returns
    -------
    ndarray, shape (n, rays, 3)
    """
    i = np.arange(rays)
    lattice = np.stack([(i + 0.5) / rays, np.mod(i * (GOLDEN_RATIO - 1.0), 1.0)], axis=1)
    u = np.mod(lattice[None, :, :] + offsets[:, None, :], 1.0)
    r = np.sqrt(u[..., 0])
    angle = 2.0 * np.pi * u[..., 1]
    up = np.sqrt(np.maximum(1.0 - u[..., 0], 0.0))
    t1, t2 = _frames(normals)
    return (
        (r * np.cos(angle))[..., None] * t1[:, None, :]
        + (r * np.sin(angle))[..., None] * t2[:, None, :]
        + up[..., None] * normals[:, None, :]
    )


def _at_hits(triangles, normals, hits):
    """Per ray: the hit triangle's vertices (k, 3), barycentric weights (k, 3) and the interpolated
    unit normal (k, 3) (rays that escaped: any triangle, zero weights and normal)."""
    hit = hits.triangle >= 0
    corners = triangles[np.where(hit, hits.triangle, 0)]
    # Embree's (u, v) may leave the triangle by a rounding error (1 - u - v = -1e-9 on an edge): clipped and
    # renormalised, every weight is >= 0, so the light that enters is >= 0 by construction
    weights = np.clip(np.stack([1.0 - hits.u - hits.v, hits.u, hits.v], axis=1), 0.0, 1.0)
    weights = weights / np.maximum(weights.sum(axis=1), 1e-300)[:, None] * hit[:, None]
    normal = np.einsum("kj,kjc->kc", weights, normals[corners])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return corners, weights, normal / np.where(length > 0.0, length, 1.0)


def _unit_normals(normals):
    normals = np.asarray(normals, dtype=np.float64)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 1e-12, length, 1.0), length[:, 0] > 1e-12


@dataclass(frozen=True)
class GatherPaths:
    """The gather's rays that bring light (:func:`gather_paths`): geometry only, so the same for every ``B``.

    Attributes
    ----------
    origin : (k,) int64
        The vertex each ray starts from (and brings light to).
    corners : (k, 3) int64
        The vertices of the triangle it meets.
    weights : (k, 3) float64
        Their barycentric weights times ``(pi / K) T12(n_p . w_k) T21(n_h . -w_k)``: the flux density the
        ray brings in per unit ``B`` at each corner, 1.
    w12 : (k, 3) float64
        The ray's refracted direction at the origin (unit, into the medium).
    stats : dict
        Counts of rays, hits and back faces.
    """

    origin: np.ndarray
    corners: np.ndarray
    weights: np.ndarray
    w12: np.ndarray
    stats: dict


def gather_paths(occluder: Occluder, points, normals, triangles, eta, *, rays: int = GATHER_RAYS, seed=SEED):
    """The rays of :func:`gather_exitance` (``K = rays`` cosine-weighted directions per vertex, turned per
    vertex by ``seed``) that meet a front face, with what each brings per unit ``B``: a :class:`GatherPaths`
    of the whole mesh. Geometry and ``eta`` only: relighting keeps them with the surface (:func:`solve_bounces`);
    without them :func:`gather_exitance` traces and uses them a block of vertices at a time."""
    blocks = list(_path_blocks(occluder, points, normals, triangles, eta, rays, seed))
    stats = {key: sum(block.stats[key] for block in blocks) for key in ("rays", "hits", "back_faces")}
    joined = {
        key: np.concatenate([getattr(block, key) for block in blocks])
        if blocks
        else np.zeros((0,) if key == "origin" else (0, 3), dtype=np.int64 if key in ("origin", "corners") else float)
        for key in ("origin", "corners", "weights", "w12")
    }
    return GatherPaths(**joined, stats=stats)


def _path_blocks(occluder, points, normals, triangles, eta, rays, seed):
    """:class:`GatherPaths` of consecutive blocks of vertices (``RAYS_PER_BLOCK`` rays each), in turn."""
    points = np.asarray(points, dtype=np.float64)
    normals, usable = _unit_normals(normals)
    triangles = np.asarray(triangles, dtype=np.int64)
    offsets = np.random.default_rng(seed).random((points.shape[0], 2))
    receivers = np.flatnonzero(usable)
    block = max(1, RAYS_PER_BLOCK // rays)
    for start in range(0, receivers.size, block):
        these = receivers[start : start + block]
        directions = cosine_directions(normals[these], rays, offsets[these]).reshape(-1, 3)
        origin = np.repeat(these, rays)
        hits = occluder.intersect(points[origin], normals[origin], directions)
        stats = {"rays": int(origin.size), "hits": 0, "back_faces": 0}
        hit = np.flatnonzero(hits.triangle >= 0)  # only these are interpolated
        hits = type(hits)(*(part[hit] for part in hits))
        directions, origin = directions[hit], origin[hit]
        corners, weights, hit_normal = _at_hits(triangles, normals, hits)
        cos_out = -np.einsum("kc,kc->k", hit_normal, directions)
        front = cos_out > 0.0
        stats["hits"] = int(hit.size)
        stats["back_faces"] = int(np.count_nonzero(~front))
        directions, origin, corners, weights = directions[front], origin[front], corners[front], weights[front]
        cos_in = np.einsum("kc,kc->k", normals[origin], directions)
        factor = (np.pi / rays) * fresnel_transmittance(cos_in, eta) * fresnel_transmittance(cos_out[front], eta)
        yield GatherPaths(origin, corners, weights * factor[:, None], refract(directions, normals[origin], eta), stats)


def gather_exitance(
    occluder: Occluder, points, normals, triangles, B, eta, *, rays: int = GATHER_RAYS, seed=SEED, paths=None
):
    """Flux density of the subsurface exitance that reaches each vertex and enters there (docs/physics.md §7.4).

    ``phi_p = (pi / K) sum_k T12(n_p . w_k, eta) T21(n_h . -w_k, eta) B(h_k)`` with ``K = rays``
    cosine-weighted directions (:func:`cosine_directions`), ``h_k`` where the ray first meets the mesh,
    ``B`` and ``n_h`` interpolated there with the barycentrics; 0 for a ray that escapes or meets a back
    face (``n_h . -w_k <= 0``).

    Parameters
    ----------
    occluder : Occluder
        The Embree scene of this mesh (``points``, ``triangles``).
    points : array_like, shape (n, 3)
        Vertices, mm.
    normals : array_like, shape (n, 3)
        Outward unit vertex normals (a zero normal receives nothing).
    triangles : array_like, shape (m, 3)
        The mesh's triangles.
    B : array_like, shape (n, C)
        Diffuse radiance factor of the light leaving the surface, W/(m² sr).
    eta : float
        Relative index of refraction (>= 1).
    rays : int
        Rays per vertex, ``K``.
    seed : int
        Seed of the per-vertex rotations.
    paths : GatherPaths, optional
        The rays already traced (:func:`gather_paths` of the same mesh, ``eta``, ``rays`` and ``seed``).

    Returns
    -------
    (phi, weighted_w12, stats)
        ``phi`` (n, C) in W/m²; ``weighted_w12`` (n, 3) the refracted directions summed with the channel
        sum of their flux density as weight (not normalised); ``stats`` counts of rays, hits, back faces.
    """
    B = np.asarray(B, dtype=np.float64)
    n, channels = B.shape
    phi = np.zeros((n, channels))
    weighted_w12 = np.zeros((n, 3))
    stats = {"rays": 0, "hits": 0, "back_faces": 0}
    # the rays traced before, or traced and used a block at a time (memory bounded by RAYS_PER_BLOCK)
    blocks = [paths] if paths is not None else _path_blocks(occluder, points, normals, triangles, eta, rays, seed)
    for block in blocks:
        entering = np.einsum("kj,kjc->kc", block.weights, B[block.corners])
        weight = entering.sum(axis=1)
        for c in range(channels):
            phi[:, c] += np.bincount(block.origin, weights=entering[:, c], minlength=n)
        for c in range(3):
            weighted_w12[:, c] += np.bincount(block.origin, weights=weight * block.w12[:, c], minlength=n)
        for key in stats:
            stats[key] += block.stats[key]
    return phi, weighted_w12, stats


#: The mirror reflection draws its light sample for blocks of vertices with this many (vertex, sample) pairs.
PAIRS_PER_BLOCK = 1 << 18


def _drawn_reflections(points, normals, usable, lights, eta, draw):
    """One light sample per vertex drawn in proportion to its reflected flux density (channel sum):
    ``(direction toward it (n, 3), reflected flux density f_j sum|f| / |f_j| (n, 3) in W/m², distance
    (n,) in mm, inf for a direction)``; zero where no sample faces the vertex (docs/physics.md §7.4)."""
    directions, irradiance, positions, intensities = [np.zeros((0, 3))], [np.zeros((0, 3))], [], []
    for light in as_light_list(lights):
        if isinstance(light, PointLight):
            positions.append(light.position_mm)
            intensities.append(light.intensity_rgb)
        else:
            drawn = light.directional_samples()
            directions.append(drawn.directions)
            irradiance.append(drawn.irradiance_rgb)
    directions, irradiance = np.concatenate(directions), np.concatenate(irradiance)
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    n, n_samples = len(points), len(directions) + len(positions)
    toward, reflected, distance = np.zeros((n, 3)), np.zeros((n, 3)), np.full(n, np.inf)
    block = max(1, PAIRS_PER_BLOCK // max(n_samples, 1))
    for lo in range(0, n if n_samples else 0, block):
        these = slice(lo, lo + block)
        b = len(points[these])
        offset = positions[None, :, :] - points[these, None, :]
        d_point = np.linalg.norm(offset, axis=2)
        w = np.concatenate(
            [
                np.broadcast_to(directions, (b, len(directions), 3)),
                offset / np.where(d_point > 0, d_point, 1.0)[..., None],
            ],
            axis=1,
        )
        e_point = [np.zeros((b, 3))] + [point_light_irradiance(rgb, d_point[:, k]) for k, rgb in enumerate(intensities)]
        e = np.concatenate(
            [np.broadcast_to(irradiance, (b, len(directions), 3)), np.stack(e_point, axis=1)[:, 1:]], axis=1
        )
        d = np.concatenate([np.full((b, len(directions)), np.inf), d_point], axis=1)
        cos = np.einsum("bi,bsi->bs", normals[these], w)
        cos = np.where(usable[these, None] & (d > 0.0) & (cos > 0.0), cos, 0.0)
        f = (fresnel_reflectance(cos, eta) * cos * (cos > 0.0))[..., None] * e
        weight = f.sum(axis=2)
        cumulative = np.cumsum(weight, axis=1)
        total = cumulative[:, -1]
        past = cumulative > (draw[these] * total)[:, None]
        last_positive = n_samples - 1 - np.argmax((weight > 0.0)[:, ::-1], axis=1)  # where rounding leaves none past
        pick = np.where(past.any(axis=1), np.argmax(past, axis=1), last_positive)
        rows = np.arange(b)
        chosen = weight[rows, pick]
        scale = np.where(chosen > 0.0, total / np.where(chosen > 0.0, chosen, 1.0), 0.0)
        toward[these] = w[rows, pick]
        reflected[these] = f[rows, pick] * scale[:, None]
        distance[these] = d[rows, pick]
    return toward, reflected, distance


def specular_reflection(
    occluder: Occluder, points, normals, areas, triangles, lights, eta, *, shadows: bool = True, seed=SEED
):
    """Flux density of the lights' mirror reflection at the boundary that reaches the surface again and
    enters there (docs/physics.md §7.4).

    At every vertex ``q`` each light sample ``j`` (facing it) reflects ``f_j = F_r(c_j, eta) E_j c_j`` (W/m²)
    toward the mirror direction. One sample per vertex is drawn with probability ``|f_j| / sum |f|``
    (``|.|`` the channel sum) and carries ``f_j sum|f| / |f_j|`` times its visibility (one shadow ray): an
    unbiased estimate with one shadow ray and one reflected ray per vertex whatever the number of
    samples. The flux ``A_q f`` (W mm²/m²) is split over the corners of the triangle the reflected ray
    meets by barycentric weight, divided by their vertex areas and multiplied by ``T12`` at the
    incidence cosine there; a ray that escapes or meets a back face deposits nothing.

    Parameters
    ----------
    occluder, points, normals, triangles
        As in :func:`gather_exitance`.
    areas : array_like, shape (n,)
        Vertex areas, mm².
    lights : light or sequence of lights
        The lights of the first solve.
    eta : float
        Relative index of refraction.
    shadows : bool
        Trace the shadow ray (off: every vertex facing the sample is lit, as in the first solve).
    seed : int
        Seed of the per-vertex draws.

    Returns
    -------
    (phi, weighted_w12, stats)
        As :func:`gather_exitance`'s (channels: 3); ``stats["reflected_flux"]`` is the flux the lights
        reflect in all and ``stats["deposited_flux"]`` what of it enters again, per channel, W mm²/m².
    """
    points = np.asarray(points, dtype=np.float64)
    normals, usable = _unit_normals(normals)
    areas = np.asarray(areas, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    n = len(points)
    draw = np.random.default_rng(seed + 1).random(n)
    w_sel, flux_sel, dist_sel = _drawn_reflections(points, normals, usable, lights, eta, draw)
    chosen = flux_sel.sum(axis=1) > 0.0
    reflected_flux = (flux_sel * areas[:, None]).sum(axis=0)
    lit = np.flatnonzero(chosen)
    if shadows and lit.size:
        visible = occluder.visible(points[lit], normals[lit], w_sel[lit], dist_sel[lit])
        lit = lit[visible]
    mirror = 2.0 * np.einsum("ij,ij->i", normals[lit], w_sel[lit])[:, None] * normals[lit] - w_sel[lit]
    hits = occluder.intersect(points[lit], normals[lit], mirror)
    corners, weights, hit_normal = _at_hits(triangles, normals, hits)
    cos_in = -np.einsum("kc,kc->k", hit_normal, mirror)
    front = (hits.triangle >= 0) & (cos_in > 0.0)
    stats = {
        "rays": int(lit.size + (np.count_nonzero(chosen) if shadows else 0)),
        "hits": int(np.count_nonzero(hits.triangle >= 0)),
        "back_faces": int(np.count_nonzero((hits.triangle >= 0) & ~front)),
        "reflected_flux": reflected_flux.tolist(),
    }
    entering = (areas[lit, None] * flux_sel[lit] * fresnel_transmittance(cos_in, eta)[:, None])[front]
    corners, weights = corners[front], weights[front]
    w12 = refract(-mirror[front], hit_normal[front], eta)
    deposited = np.zeros((n, 3))
    weighted_w12 = np.zeros((n, 3))
    for j in range(3):
        for c in range(3):
            deposited[:, c] += np.bincount(corners[:, j], weights=weights[:, j] * entering[:, c], minlength=n)
            weighted_w12[:, c] += np.bincount(
                corners[:, j], weights=weights[:, j] * entering.sum(axis=1) * w12[:, c], minlength=n
            )
    stats["deposited_flux"] = deposited.sum(axis=0).tolist()
    phi = deposited / np.where(areas > 0.0, areas, np.inf)[:, None]
    weighted_w12 /= np.where(areas > 0.0, areas, np.inf)[:, None]  # weights as flux density, like the gather
    return phi, weighted_w12, stats


def reentering_light(
    occluder: Occluder,
    points,
    normals,
    areas,
    triangles,
    B,
    eta,
    *,
    lights=None,
    shadows: bool = True,
    rays: int = GATHER_RAYS,
    seed=SEED,
    paths=None,
) -> ReenteringLight:
    """The solver's input for one bounce: the exitance ``T21 B`` gathered (:func:`gather_exitance`)
    plus, when ``lights`` are given, their mirror reflection (:func:`specular_reflection`); the
    refracted direction is the flux-weighted mean of both (docs/physics.md §7.2, §7.4); ``paths``: the
    gather's rays traced before (:func:`gather_paths`)."""
    normals = np.asarray(normals, dtype=np.float64)
    t = time.perf_counter()
    phi, weighted_w12, gather_stats = gather_exitance(
        occluder, points, normals, triangles, B, eta, rays=rays, seed=seed, paths=paths
    )
    stats = {"gather": gather_stats, "seconds": {"gather": time.perf_counter() - t, "specular": 0.0}}
    if lights is not None:
        t = time.perf_counter()
        phi_s, w12_s, specular_stats = specular_reflection(
            occluder, points, normals, areas, triangles, lights, eta, shadows=shadows, seed=seed
        )
        phi = phi + phi_s
        weighted_w12 = weighted_w12 + w12_s
        stats["specular"] = specular_stats
        stats["seconds"]["specular"] = time.perf_counter() - t
    length = np.linalg.norm(weighted_w12, axis=1, keepdims=True)
    inward = -_unit_normals(normals)[0]
    inward[np.all(inward == 0.0, axis=1)] = (0.0, 0.0, -1.0)
    w12 = np.where(length > 0.0, weighted_w12 / np.where(length > 0.0, length, 1.0), inward)
    return ReenteringLight(phi, w12, stats)


#: The gather's rays of relighting's bounces, kept per (surface, eta, rays, seed): every later light bounces too.
_GATHERS = PerSurface("bounce gather rays")


def solve_bounces(
    geometry,
    occluder: Occluder,
    B,
    lights,
    medium,
    *,
    bounces: int,
    model: str,
    method: str,
    tol: float,
    device: str = DEFAULT_DEVICE,
    shadows: bool = True,
    rays: int = GATHER_RAYS,
    progress=None,
    memory_limit=None,
    time_limit=None,
    solver=None,
) -> Bounces:
    """The light that re-enters, ``bounces`` times (docs/physics.md §7.4).

    ``B_1 = solve(gather(B_0) + specular(lights))`` and ``B_{k+1} = solve(gather(B_k))``, each solve with
    the same medium, model and method as the first (:func:`translucency.scatter.solve.solve`) and the
    tolerance ``tol`` times :data:`BOUNCE_TOL_FACTOR` (at most :data:`MAX_BOUNCE_TOL`; ``exact`` has none;
    ``relight`` applies the first solve's operators again, at ``tol``).

    Parameters
    ----------
    geometry : SurfaceGeometry
        The solver's mesh (mm), the one ``occluder`` was built on.
    occluder : Occluder
        Its Embree scene.
    B : array_like, shape (n, C)
        The first solve's diffuse radiance factor, W/(m² sr).
    lights : light or sequence of lights
        The first solve's lights (for their mirror reflection).
    medium, model, method, tol, device, memory_limit, time_limit
        As in :func:`~translucency.scatter.solve.solve`.
    bounces : int
        How many times (0 to :data:`~translucency.scatter.names.MAX_BOUNCES`).
    shadows : bool
        Whether the first solve cast shadow rays (the mirror reflection follows it).
    rays : int
        Rays per vertex of the gather.
    progress : callable, optional
        ``progress(stage, fraction)`` with stage ``"bounces"``.
    solver : callable, optional
        Stands in for :func:`~translucency.scatter.solve.solve` (the same arguments), as the first solve's did.

    Returns
    -------
    Bounces
    """
    from .solve import solve

    bounces = check_bounces(bounces)
    # relight keeps one set of operators per surface: the bounces reuse the first solve's, at its tol
    bounce_tol = tol if method == "relight" else max(min(tol * BOUNCE_TOL_FACTOR, MAX_BOUNCE_TOL), tol)
    report = progress or (lambda stage, fraction: None)
    previous = np.asarray(B, dtype=np.float64)
    total = np.zeros_like(previous)
    orders, solutions, entered = [], [], []
    seconds = {"gather": 0.0, "specular": 0.0, "solve": 0.0}
    rays_cast = 0
    mirror = {"reflected_flux": None, "deposited_flux": None}
    for k in range(bounces):
        report("bounces", k / max(bounces, 1))
        paths = None
        if method == "relight":  # relighting: every later light bounces too, so the rays are kept
            t = time.perf_counter()
            paths = _GATHERS.get(
                geometry,
                (float(medium.eta), rays, SEED + k),
                lambda seed=SEED + k: gather_paths(
                    occluder, geometry.points, geometry.normals, geometry.triangles, medium.eta, rays=rays, seed=seed
                ),
            )
            seconds["gather"] += time.perf_counter() - t
        light = reentering_light(
            occluder,
            geometry.points,
            geometry.normals,
            geometry.vertex_areas,
            geometry.triangles,
            previous,
            medium.eta,
            lights=lights if k == 0 else None,
            shadows=shadows,
            rays=rays,
            seed=SEED + k,
            paths=paths,
        )
        seconds["gather"] += light.stats["seconds"]["gather"]
        seconds["specular"] += light.stats["seconds"]["specular"]
        rays_cast += light.stats["gather"]["rays"] + light.stats.get("specular", {}).get("rays", 0)
        if "specular" in light.stats:
            mirror = {key: light.stats["specular"][key] for key in ("reflected_flux", "deposited_flux")}
        entered.append((light.phi_rgb * geometry.vertex_areas[:, None]).sum(axis=0).tolist())
        t = time.perf_counter()
        solution = (solver or solve)(
            geometry,
            light.phi_rgb,
            light.w12,
            medium,
            model=model,
            method=method,
            tol=bounce_tol,
            device=device,
            memory_limit=memory_limit,
            time_limit=time_limit,
        )
        seconds["solve"] += time.perf_counter() - t
        previous = solution.B
        total = total + previous
        orders.append(previous)
        solutions.append(solution)
    report("bounces", 1.0)
    stats = {
        "bounces": bounces,
        "rays_per_vertex": rays,
        "tol": bounce_tol,
        "rays": rays_cast,
        "entered_flux": entered,
        "mirror": mirror,
        "seconds": seconds,
    }
    return Bounces(total, orders, stats, solutions)
