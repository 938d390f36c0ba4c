"""Radiance leaving a closed mesh along its normals, path-traced by Mitsuba 3 (an independent check).

The scene: the closed triangle mesh, flat-shaded (``face_normals``: the object is the polyhedron),
with a smooth ``dielectric`` boundary of ``int_ior = eta``, ``ext_ior = 1`` (docs/physics.md §1.2)
around a ``homogeneous`` medium (``sigma_t = sigma_a + sigma_s`` in 1/mm, ``albedo = sigma_s /
sigma_t``, Henyey-Greenstein ``g``; the mesh stays in mm, so the coefficients keep their 1/mm with
``scale = 1``); a small spherical area light far away in ``light_direction`` and nothing else (a
black background). Mitsuba's ``volpath`` integrator estimates, per sensor point, the radiance that
arrives at ``point + epsilon normal`` travelling along ``-normal``: the radiance leaving the surface
along the normal, which is what the models output per vertex (docs/physics.md §5.3,
``L = T21(eta, 1) B``).

Why a small area light and not a directional one: behind a smooth dielectric a path can only reach a
light by being refracted out of the object and hitting it, which has probability zero for a delta
(directional) light. A sphere of angular radius ``delta`` seen from the object, with uniform radiance

    L_e = E / (pi sin^2 delta)                                      [W/(m^2 sr)]

gives exactly the irradiance ``E`` on a surface facing it, and an illumination that tends to the
directional light of irradiance ``E`` as ``delta -> 0``. For a response linear in the cosine of the
incident direction the finite cone adds nothing; the rest is a bias of order ``delta^2`` (measured by
``bench/reference_mitsuba.py`` with two half-angles). The light sits ``1e4`` times the mesh's
half-diagonal away, so its direction and size vary over the object by about 1e-4 rad.

Each channel is traced on its own with the channel's coefficients in all three RGB slots: Mitsuba's
``volpath`` samples distances with one channel and weights the others by transmittance ratios, whose
product over the hundreds of events of a high-albedo walk has an exploding variance.

Russian roulette in ``volpath`` keeps a path with probability ``min(throughput * eta^2, 0.95)``; in a
medium of albedo above 0.95 that cap makes the surviving weights grow by ``albedo / 0.95`` per event
and the variance diverge. There roulette is switched off (``rr_depth = max_depth``) and paths end
when they leave the object or after ``max_depth`` events, chosen so that ``albedo^max_depth <= 1e-6``
(the weight any truncated path still carried). At albedo 0.95 or below, roulette from the tenth event
is the analogue absorption and stays on.

The standard error is that of batch means: the samples of each point are traced in ``n_batches``
independent renders (seeds ``seed * n_batches + b``), ``stderr = std(batch means) / sqrt(n_batches)``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidParameterError, MeshError
from ..geometry.measure import signed_volume
from ..geometry.topology import unique_edges
from ..scatter.medium import Medium

__all__ = ["VolpathRadiance", "volpath_radiance", "light_radiance", "depth_settings", "VARIANTS"]

#: Mitsuba variants the check runs on (RGB: the three slots carry one channel's coefficients at a time).
#: ``llvm_ad_rgb`` needs libLLVM 16 or newer (Debian 12: ``libllvm19``; with LLVM 15 Mitsuba 3.9's kernels
#: fail to compile); ``scalar_rgb`` needs neither LLVM nor CUDA.
VARIANTS = ("scalar_rgb", "llvm_ad_rgb", "cuda_ad_rgb")
#: Distance of the light from the mesh's centre, in half-diagonals of its bounding box.
LIGHT_DISTANCE = 1e4
#: Sensor rays start this many bounding-box diagonals outside the surface.
SENSOR_OFFSET = 1e-5
#: Highest albedo at which Mitsuba's Russian roulette (survival capped at 0.95) is left on.
ROULETTE_ALBEDO = 0.95
#: Largest weight a path cut off at ``max_depth`` may still carry (``albedo^max_depth``).
TRUNCATED_WEIGHT = 1e-6


@dataclass(frozen=True)
class VolpathRadiance:
    """Radiance along the normal at sensor points, from Mitsuba's ``volpath``, with what reproduces it.

    Attributes
    ----------
    radiance : ndarray, shape (k, C)
        Radiance leaving each sensor point along its normal, W/(m^2 sr) for ``irradiance`` in W/m^2.
    stderr : ndarray, shape (k, C)
        Standard error of ``radiance`` (batch means), same unit.
    spp : int
        Samples per sensor point and channel actually traced (a multiple of ``n_batches``).
    n_batches : int
        Independent renders the samples were split into.
    seed : int
        Seed of the first batch is ``seed * n_batches``.
    irradiance : float
        Irradiance on a surface facing the light, W/m^2.
    light_half_angle_deg : float
        Angular radius of the spherical light seen from the mesh, degrees.
    light_radiance : float
        Radiance of the light, ``irradiance / (pi sin^2 delta)``, W/(m^2 sr).
    light_distance_mm : float
        Distance from the mesh's bounding-box centre to the light's centre, mm.
    sensor_offset_mm : float
        How far outside the surface each sensor ray starts, mm.
    max_depth, rr_depth : tuple of int
        ``volpath`` settings per channel (-1: no limit).
    variant : str
        The Mitsuba variant used.
    mitsuba_version : str
        Mitsuba's version.
    seconds : tuple of float
        Wall time per channel, s (0 for a channel that repeats an earlier one's coefficients).
    """

    radiance: np.ndarray
    stderr: np.ndarray
    spp: int
    n_batches: int
    seed: int
    irradiance: float
    light_half_angle_deg: float
    light_radiance: float
    light_distance_mm: float
    sensor_offset_mm: float
    max_depth: tuple
    rr_depth: tuple
    variant: str
    mitsuba_version: str
    seconds: tuple

    @property
    def relative_stderr(self) -> np.ndarray:
        """``stderr / radiance`` (inf where the radiance is 0), shape (k, C)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.radiance > 0, self.stderr / np.where(self.radiance > 0, self.radiance, 1), np.inf)


def light_radiance(irradiance: float, half_angle_deg: float) -> float:
    """Radiance of a uniform sphere of angular radius ``half_angle_deg`` giving ``irradiance`` on a facing surface.

    ``L_e = E / (pi sin^2 delta)`` in W/(m^2 sr) for ``E`` in W/m^2: a facing surface sees the sphere
    as a cap of half-angle ``delta``, and the cosine-weighted solid angle of that cap is
    ``pi sin^2 delta``.
    """
    return float(irradiance) / (math.pi * math.sin(math.radians(half_angle_deg)) ** 2)


def depth_settings(albedo: float, max_depth=None, rr_depth=None) -> tuple[int, int]:
    """``(max_depth, rr_depth)`` for ``volpath`` in a medium of single-scattering albedo ``albedo``.

    At albedo at most :data:`ROULETTE_ALBEDO`: no depth limit (-1) and roulette from the tenth event.
    Above it: no roulette, and a depth limit where ``albedo^max_depth <= TRUNCATED_WEIGHT`` (at least
    1000; none at albedo 1, where only leaving the object ends a path). Given values win.
    """
    if albedo <= ROULETTE_ALBEDO:
        depth = -1 if max_depth is None else int(max_depth)
        return depth, 10 if rr_depth is None else int(rr_depth)
    if max_depth is None:
        max_depth = -1 if albedo >= 1.0 else max(1000, math.ceil(math.log(TRUNCATED_WEIGHT) / math.log(albedo)))
    if rr_depth is None:
        rr_depth = 2**30 if max_depth < 0 else max_depth
    return int(max_depth), int(rr_depth)


def _mitsuba(variant: str):
    """Mitsuba with ``variant`` selected; a sentence saying how to install it when it is missing."""
    if variant not in VARIANTS:
        raise InvalidParameterError(f"variant must be one of {', '.join(VARIANTS)}, got {variant!r}.")
    try:
        import mitsuba as mi
    except ImportError:
        raise ImportError(
            'Mitsuba 3 is not installed: install the reference extra with `pip install -e ".[reference]"`.'
        ) from None
    if variant not in mi.variants():
        raise InvalidParameterError(
            f"this Mitsuba build has no variant {variant!r}; pick one of "
            f"{', '.join(v for v in VARIANTS if v in mi.variants())}."
        )
    mi.set_variant(variant)
    return mi


def _check_mesh(points, triangles):
    points = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 4 or not np.all(np.isfinite(points)):
        raise MeshError(f"points must be a finite (n, 3) array of at least 4 vertices in mm, got shape {points.shape}.")
    if triangles.ndim != 2 or triangles.shape[1] != 3 or len(triangles) < 4 or triangles.dtype.kind not in "iu":
        raise MeshError(f"triangles must be an (m, 3) integer array of at least 4 faces, got shape {triangles.shape}.")
    triangles = triangles.astype(np.int64)
    if triangles.min() < 0 or triangles.max() >= len(points):
        raise MeshError(f"triangles must index the {len(points)} points (0 to {len(points) - 1}).")
    _, edge_of_corner = unique_edges(triangles)
    uses = np.bincount(edge_of_corner.ravel())
    if np.any(uses != 2):
        raise MeshError(
            f"the mesh must be closed (every edge shared by two triangles), but {int(np.sum(uses != 2))} edges are "
            "not; close it (translucency.io.clean) before tracing a medium inside it."
        )
    if signed_volume(points, triangles) <= 0:
        raise MeshError("the triangles must be wound counter-clockwise seen from outside (outward normals); flip them.")
    return points, triangles


def _check_sensors(sensor_points, sensor_normals):
    p = np.asarray(sensor_points, dtype=np.float64)
    n = np.asarray(sensor_normals, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) == 0 or n.shape != p.shape:
        raise InvalidParameterError(
            f"sensor_points_mm and sensor_normals must be (k, 3) arrays of the same shape, got {p.shape} and {n.shape}."
        )
    length = np.linalg.norm(n, axis=1)
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(n))) or np.any(length < 1e-12):
        raise InvalidParameterError("sensor_points_mm and sensor_normals must be finite, with non-zero normals.")
    return p, n / length[:, None]


def _unit(direction, name):
    d = np.asarray(direction, dtype=np.float64)
    length = float(np.linalg.norm(d)) if d.shape == (3,) else 0.0
    if not np.isfinite(length) or length < 1e-12:
        raise InvalidParameterError(f"{name} must be a non-zero 3-vector, got {direction!r}.")
    return d / length


def _mesh(mi, points, triangles, eta, sigma_t, albedo, g):
    props = mi.Properties()
    props["face_normals"] = True
    props["bsdf"] = mi.load_dict({"type": "dielectric", "int_ior": float(eta), "ext_ior": 1.0})
    props["interior"] = mi.load_dict(
        {
            "type": "homogeneous",
            "sigma_t": float(sigma_t),
            "albedo": float(albedo),
            "scale": 1.0,
            "phase": {"type": "hg", "g": float(g)},
        }
    )
    mesh = mi.Mesh("object", len(points), len(triangles), props)
    params = mi.traverse(mesh)
    positions = points.astype(np.float32).ravel()
    faces = triangles.astype(np.uint32).ravel()
    if mi.variant().startswith("scalar"):
        params["vertex_positions"] = positions.tolist()
        params["faces"] = faces.tolist()
    else:
        params["vertex_positions"] = mi.Float(positions)
        params["faces"] = mi.UInt32(faces)
    params.update()
    return mesh


def _sensor(mi, origins, directions):
    """One ``batch`` sensor of radiance meters, pixel ``i`` of a (k x 1) film being sensor point ``i``."""
    film = {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"}, "pixel_format": "rgb"}
    meters = {
        f"meter{i:06d}": {"type": "radiancemeter", "origin": o.tolist(), "direction": d.tolist(), "film": film}
        for i, (o, d) in enumerate(zip(origins, directions))
    }
    return {
        "type": "batch",
        **meters,
        "film": {
            "type": "hdrfilm",
            "width": len(origins),
            "height": 1,
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
        "sampler": {"type": "independent", "sample_count": 1},
    }


def volpath_radiance(
    points_mm,
    triangles,
    sensor_points_mm,
    sensor_normals,
    medium: Medium,
    light_direction,
    *,
    light_half_angle_deg: float = 4.0,
    irradiance: float = 1.0,
    spp: int = 4096,
    n_batches: int = 16,
    seed: int = 0,
    max_depth=None,
    rr_depth=None,
    variant: str = "scalar_rgb",
) -> VolpathRadiance:
    """Radiance leaving a closed mesh along the normal at sensor points, path-traced by Mitsuba's ``volpath``.

    Parameters
    ----------
    points_mm : array_like, shape (n, 3)
        Vertex positions of a closed mesh, mm.
    triangles : array_like of int, shape (m, 3)
        Triangles wound counter-clockwise seen from outside; every edge shared by two of them.
    sensor_points_mm : array_like, shape (k, 3)
        Points on the surface where the radiance is estimated, mm (face centroids suit a
        polyhedron: the ray along ``-normal`` meets that face, whose normal it must be).
    sensor_normals : array_like, shape (k, 3)
        Outward normals at the sensor points (normalised here).
    medium : Medium
        The interior: ``sigma_a``, ``sigma_s`` (unreduced, 1/mm), ``g`` per channel and ``eta``.
    light_direction : array_like, shape (3,)
        Direction from the object toward the light (normalised here).
    light_half_angle_deg : float, optional
        Angular radius of the spherical light seen from the object, degrees, in (0, 30]. The
        result tends to that of a directional light as this goes to 0, with a bias of order its
        square; the variance grows as its inverse square.
    irradiance : float, optional
        Irradiance on a surface facing the light, W/m^2 (the light's radiance is
        :func:`light_radiance`).
    spp : int, optional
        Samples per sensor point and channel; rounded up to a multiple of ``n_batches``.
    n_batches : int, optional
        Independent renders for the batch-means standard error (>= 2).
    seed : int, optional
        Seed (>= 0). For given ``(seed, n_batches, spp)``, sensors and depth settings the result
        repeats bit for bit in ``scalar_rgb`` and to rounding in the vectorised variants (their sums
        run in a varying order).
    max_depth, rr_depth : int, optional
        ``volpath``'s depth limit and first roulette depth; by default :func:`depth_settings` of
        each channel's albedo.
    variant : str, optional
        Mitsuba variant, one of :data:`VARIANTS` (``scalar_rgb`` needs no LLVM or CUDA; it uses every
        core through Mitsuba's block scheduler). Selecting it changes Mitsuba's global variant.

    Returns
    -------
    VolpathRadiance
        Radiance and standard error per point and channel (W/(m^2 sr) for ``irradiance`` in W/m^2)
        and every setting that reproduces them.

    Raises
    ------
    MeshError
        For a mesh that is not closed or not wound outward, or malformed arrays.
    InvalidParameterError
        For bad sensors, light or sampling settings, and when a sensor sees the light mirrored in
        the boundary (its normal within ``light_half_angle_deg`` of the light direction, ``eta > 1``).
    ImportError
        When Mitsuba is not installed (the ``reference`` extra).
    """
    if not isinstance(medium, Medium):
        raise InvalidParameterError(f"medium must be a translucency Medium, got {type(medium).__name__}.")
    points, triangles = _check_mesh(points_mm, triangles)
    sensor_points, normals = _check_sensors(sensor_points_mm, sensor_normals)
    towards_light = _unit(light_direction, "light_direction")
    half_angle = float(light_half_angle_deg)
    if not 0.0 < half_angle <= 30.0:
        raise InvalidParameterError(f"light_half_angle_deg must lie in (0, 30] degrees, got {light_half_angle_deg!r}.")
    if not (math.isfinite(irradiance) and irradiance > 0):
        raise InvalidParameterError(f"irradiance must be a positive number of W/m^2, got {irradiance!r}.")
    if int(n_batches) < 2 or int(spp) < 1:
        raise InvalidParameterError(f"spp must be >= 1 and n_batches >= 2, got spp={spp!r}, n_batches={n_batches!r}.")
    if int(seed) < 0:
        raise InvalidParameterError(f"seed must be >= 0, got {seed!r}.")
    n_batches = int(n_batches)
    spp_batch = -(-int(spp) // n_batches)
    if medium.eta > 1.0:
        mirrored = np.flatnonzero(normals @ towards_light > math.cos(math.radians(half_angle)))
        if mirrored.size:
            raise InvalidParameterError(
                f"sensor points {mirrored[:5].tolist()}{' ...' if mirrored.size > 5 else ''} ({mirrored.size} in "
                f"all) see the light mirrored in the boundary (normal within {half_angle} deg of the light direction); "
                "drop them or tilt the light."
            )

    mi = _mitsuba(variant)
    lo, hi = points.min(axis=0), points.max(axis=0)
    half_diagonal = 0.5 * float(np.linalg.norm(hi - lo))
    distance = LIGHT_DISTANCE * half_diagonal
    offset = SENSOR_OFFSET * 2.0 * half_diagonal
    radiance_e = light_radiance(irradiance, half_angle)
    light = {
        "type": "sphere",
        "center": (0.5 * (lo + hi) + distance * towards_light).tolist(),
        "radius": distance * math.sin(math.radians(half_angle)),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [radiance_e] * 3}},
    }
    sensor = _sensor(mi, sensor_points + offset * normals, -normals)

    k, channels = len(sensor_points), medium.n_channels
    radiance = np.zeros((k, channels))
    stderr = np.zeros((k, channels))
    depths, roulettes, seconds = [], [], []
    done = {}
    for c in range(channels):
        sigma_t = float(medium.sigma_a[c] + medium.sigma_s[c])
        albedo = float(medium.sigma_s[c]) / sigma_t
        depth, roulette = depth_settings(albedo, max_depth, rr_depth)
        depths.append(depth)
        roulettes.append(roulette)
        key = (float(medium.sigma_a[c]), float(medium.sigma_s[c]), float(medium.g[c]))
        if key in done:
            radiance[:, c], stderr[:, c] = radiance[:, done[key]], stderr[:, done[key]]
            seconds.append(0.0)
            continue
        start = time.perf_counter()
        scene = mi.load_dict(
            {
                "type": "scene",
                "object": _mesh(mi, points, triangles, medium.eta, sigma_t, albedo, medium.g[c]),
                "light": light,
                "sensor": sensor,
            }
        )
        integrator = mi.load_dict({"type": "volpath", "max_depth": depth, "rr_depth": roulette, "block_size": 1})
        batches = np.empty((n_batches, k))
        for b in range(n_batches):
            image = mi.render(scene, integrator=integrator, spp=spp_batch, seed=int(seed) * n_batches + b)
            batches[b] = np.asarray(image, dtype=np.float64).reshape(k, -1)[:, 0]
        radiance[:, c] = batches.mean(axis=0)
        stderr[:, c] = batches.std(axis=0, ddof=1) / math.sqrt(n_batches)
        seconds.append(time.perf_counter() - start)
        done[key] = c

    return VolpathRadiance(
        radiance=radiance,
        stderr=stderr,
        spp=spp_batch * n_batches,
        n_batches=n_batches,
        seed=int(seed),
        irradiance=float(irradiance),
        light_half_angle_deg=half_angle,
        light_radiance=radiance_e,
        light_distance_mm=distance,
        sensor_offset_mm=offset,
        max_depth=tuple(depths),
        rr_depth=tuple(roulettes),
        variant=variant,
        mitsuba_version=str(mi.__version__),
        seconds=tuple(seconds),
    )
