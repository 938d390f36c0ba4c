"""Light sources: directional, point and environment lights, validated once on construction.

Every light describes the light arriving at the surface from outside; what enters the medium
(Fresnel ``T12``, the cosine, shadows) is :mod:`translucency.scatter.irradiance`'s job. An
:class:`EnvironmentLight` is expanded into a set of directional samples
(:meth:`EnvironmentLight.directional_samples`), so the rest of the pipeline only knows two kinds of
source: a direction (a light at infinity) and a position (a point light).

Units. Lengths are mm inside the library; radiometric quantities keep the user's area unit, W/m².
Nothing is converted between the two, and nothing needs to be: a vertex area ``A`` in mm² times an
irradiance ``E`` in W/m² is a flux in ``W mm² / m²`` (= 1e-6 W), and the BSSRDF ``S_d`` in
1/(mm² sr) times that flux is a radiance in W/(m² sr). So with ``E`` in W/m² the solver's
``B = sum S_d Phi`` comes out in W/(m² sr), the unit of the environment radiance, and a white
Lambertian reflector lit by ``E`` would show ``E / pi`` in the same unit. The one place a length
enters a radiometric quantity is the inverse-square law of a point light: there the distance is
converted to metres, ``E = I / (d_mm / 1000)**2``, so that ``I`` is in W/sr and ``E`` in W/m².

Equirectangular maps (environment radiance images): row 0 is the zenith (``up``), the last row the
nadir; the polar angle ``theta`` grows linearly down the rows and the azimuth ``phi`` linearly
along the columns, ``phi = 0`` at the left edge. The direction of ``(theta, phi)`` is
``sin(theta) cos(phi) e1 + sin(theta) sin(phi) e2 + cos(theta) up`` with ``e1`` the world axis
``+x`` made orthogonal to ``up`` (``+y`` when ``up`` is along x) and ``e2 = up x e1``.

============== ================================================================ ============
symbol         meaning                                                          unit
============== ================================================================ ============
w_i            unit vector from the surface toward the light                    1
E              irradiance on a surface facing the light (directional light)     W/m²
I              radiant intensity of a point light                               W/sr
d              distance from a point light to the surface point                 mm
L              radiance of the environment                                      W/(m² sr)
dw             solid angle represented by one environment sample                sr
E_k = L dw     irradiance weight of environment sample k                        W/m²
N              number of environment directions                                 1
============== ================================================================ ============
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidParameterError

__all__ = [
    "DirectionalLight",
    "PointLight",
    "EnvironmentLight",
    "DirectionalSamples",
    "point_light_irradiance",
    "cosine_integral_error",
    "as_light_list",
    "MM_PER_M",
]

MM_PER_M = 1000.0
"""Millimetres per metre: point-light distances (mm) are converted with it for ``E = I / d_m**2``."""

SAMPLING_METHODS = ("stratified", "importance")
MAX_DIRECTIONS = 1_000_000
GOLDEN_RATIO = (1.0 + math.sqrt(5.0)) / 2.0
LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 luminance of linear RGB


def _vector3(value, what: str, name: str) -> np.ndarray:
    """Three finite floats, or an InvalidParameterError sentence naming ``name``."""
    try:
        v = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{what}: {name} must be three numbers, got {value!r}.") from None
    if v.shape != (3,):
        raise InvalidParameterError(f"{what}: {name} must be three numbers (x, y, z), got shape {v.shape}.")
    if not np.all(np.isfinite(v)):
        raise InvalidParameterError(f"{what}: {name} must be finite, got {v.tolist()}.")
    return v


def _rgb(value, what: str, name: str, unit: str) -> np.ndarray:
    """One non-negative finite number (grey) or one per RGB channel, as a read-only (3,) array."""
    try:
        v = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{what}: {name} must be a number or three RGB numbers, got {value!r}.") from None
    if v.ndim == 0:
        v = np.full(3, float(v))
    if v.shape != (3,):
        raise InvalidParameterError(
            f"{what}: {name} must be one number or three RGB numbers ({unit}), got shape {v.shape}."
        )
    if not np.all(np.isfinite(v)):
        raise InvalidParameterError(f"{what}: {name} must be finite, got {v.tolist()}.")
    if np.any(v < 0):
        raise InvalidParameterError(f"{what}: {name} must be >= 0 ({unit}) in every channel, got {v.tolist()}.")
    v.setflags(write=False)
    return v


def unit_vector(vector) -> np.ndarray:
    """``vector`` divided by its length, for any finite non-zero length (1e-300 to 1e300 included).

    The vector is first divided by its largest absolute component, so that the squares summed for
    the length neither overflow nor underflow. Returns an (n,) float64 array of unit length, or
    all-NaN for a zero or non-finite vector (the callers refuse those with a sentence).
    """
    v = np.asarray(vector, dtype=np.float64)
    largest = float(np.max(np.abs(v))) if v.size else 0.0
    if not (np.isfinite(largest) and largest > 0.0):
        return np.full(v.shape, np.nan)
    v = v / largest
    return v / np.linalg.norm(v)


def _unit(value, what: str, name: str) -> np.ndarray:
    v = _vector3(value, what, name)
    if not np.any(v):
        raise InvalidParameterError(f"{what}: {name} must have a non-zero length, got {v.tolist()}.")
    v = unit_vector(v)
    v.setflags(write=False)
    return v


@dataclass(frozen=True, eq=False)
class DirectionalSamples:
    """A set of lights at infinity: unit directions toward the light and their irradiance weights.

    Attributes
    ----------
    directions : ndarray, shape (k, 3)
        Unit vectors from the surface toward each light direction ``w_i``.
    irradiance_rgb : ndarray, shape (k, 3)
        Irradiance ``E_k`` of each direction on a surface facing it, W/m².
    solid_angle : ndarray, shape (k,)
        Solid angle ``dw`` each sample stands for, sr (``E_k = L dw``; 0 for a true directional
        light, which has no extent).
    """

    directions: np.ndarray
    irradiance_rgb: np.ndarray
    solid_angle: np.ndarray

    def __len__(self) -> int:
        return len(self.directions)


@dataclass(frozen=True, eq=False)
class DirectionalLight:
    """A light at infinity (sun-like): parallel rays from ``direction``.

    Parameters
    ----------
    direction : sequence of 3 float
        Vector from the object toward the light (normalised on construction; any non-zero length).
    irradiance_rgb : float or sequence of 3 float, optional
        Irradiance ``E`` on a surface facing the light, W/m², per channel (one number: grey).
    """

    direction: np.ndarray
    irradiance_rgb: np.ndarray = 1.0

    def __post_init__(self):
        object.__setattr__(self, "direction", _unit(self.direction, "DirectionalLight", "direction"))
        object.__setattr__(
            self, "irradiance_rgb", _rgb(self.irradiance_rgb, "DirectionalLight", "irradiance_rgb", "W/m²")
        )

    def directional_samples(self) -> DirectionalSamples:
        """This light as a one-sample :class:`DirectionalSamples`."""
        return DirectionalSamples(self.direction[None, :], self.irradiance_rgb[None, :], np.zeros(1))

    def to_dict(self) -> dict:
        """Plain description for metadata."""
        return {
            "type": "directional",
            "direction": self.direction.tolist(),
            "irradiance_rgb_W_m2": self.irradiance_rgb.tolist(),
        }


@dataclass(frozen=True, eq=False)
class PointLight:
    """An isotropic point light with inverse-square fall-off.

    Parameters
    ----------
    position_mm : sequence of 3 float
        Position of the light, mm, in the mesh's coordinates.
    intensity_rgb : float or sequence of 3 float, optional
        Radiant intensity ``I``, W/sr, per channel. The irradiance on a surface facing the light at
        distance ``d`` (mm) is ``E = I / (d / 1000)**2`` in W/m² (:func:`point_light_irradiance`).
    """

    position_mm: np.ndarray
    intensity_rgb: np.ndarray = 1.0

    def __post_init__(self):
        position = _vector3(self.position_mm, "PointLight", "position_mm")
        position.setflags(write=False)
        object.__setattr__(self, "position_mm", position)
        object.__setattr__(self, "intensity_rgb", _rgb(self.intensity_rgb, "PointLight", "intensity_rgb", "W/sr"))

    def to_dict(self) -> dict:
        """Plain description for metadata."""
        return {
            "type": "point",
            "position_mm": self.position_mm.tolist(),
            "intensity_rgb_W_sr": self.intensity_rgb.tolist(),
        }


POINT_LIGHT_MIN_DISTANCE_MM = 1e-3
"""Distances below 1 µm are raised to it in :func:`point_light_irradiance` (a light on the surface)."""


def point_light_irradiance(intensity_rgb, distance_mm):
    """Irradiance of a point light on a surface facing it, ``E = I / d_m**2`` in W/m².

    Parameters
    ----------
    intensity_rgb : array_like, shape (3,)
        Radiant intensity ``I``, W/sr.
    distance_mm : array_like, shape (n,)
        Distances from the light, mm; values below ``POINT_LIGHT_MIN_DISTANCE_MM`` are raised to it
        (the only clamp; callers count it).

    Returns
    -------
    ndarray, shape (n, 3)
        ``E = I / (d / MM_PER_M)**2``, W/m² (inverse-square law with the distance in metres).
    """
    d_m = np.maximum(np.asarray(distance_mm, dtype=np.float64), POINT_LIGHT_MIN_DISTANCE_MM) / MM_PER_M
    return np.asarray(intensity_rgb, dtype=np.float64)[None, :] / (d_m * d_m)[:, None]


def _frame(up: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axes ``e1, e2`` completing ``up`` to a right-handed frame (``e1`` = world +x made orthogonal)."""
    reference = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = reference - np.dot(reference, up) * up
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(up, e1)


def _stratified_sphere(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` directions, one uniformly distributed in each of ``n`` equal-area zones of the sphere.

    Zone ``k`` is the band ``1 - 2(k+1)/n <= z <= 1 - 2k/n`` (area ``4 pi / n``); its sample has a
    jittered height in the band and the azimuth of a spherical Fibonacci lattice turned by a random
    angle, so the set is stratified (unbiased) and close to a low-discrepancy lattice.

    Returns
    -------
    cos_theta, phi : ndarray, shape (n,)
    """
    k = np.arange(n, dtype=np.float64)
    cos_theta = 1.0 - 2.0 * (k + rng.random(n)) / n
    phi = 2.0 * np.pi * np.mod(k / GOLDEN_RATIO + rng.random(), 1.0)
    return cos_theta, phi


@dataclass(frozen=True, eq=False)
class EnvironmentLight:
    """Light arriving from every direction: a constant colour or an equirectangular radiance map.

    The environment is integrated with ``n_directions`` directional samples
    (:meth:`directional_samples`): ``"stratified"`` places one sample in each of ``n_directions``
    equal-area zones of the sphere (weight ``L(w) 4 pi / N``); ``"importance"`` picks map pixels with
    probability proportional to luminance times pixel solid angle (systematic resampling of the CDF)
    and a uniform direction inside each picked pixel (weight ``L dw / (N P)``). A constant
    environment is sampled the same way by both. :func:`cosine_integral_error` states the
    integration error of a sample set.

    Parameters
    ----------
    radiance_rgb : float or sequence of 3 float, optional
        Constant radiance ``L``, W/(m² sr); used when ``radiance_map`` is None.
    radiance_map : array_like, shape (H, W, 3), optional
        Equirectangular radiance image, W/(m² sr), linear RGB (module docstring for its axes); read
        files with :func:`translucency.io.envmap.read_equirectangular`.
    n_directions : int, optional
        Number of sample directions ``N`` (default 256).
    sampling : {"stratified", "importance"}, optional
    seed : int, optional
        Seed of the jitter (the samples are a deterministic function of the light).
    up : sequence of 3 float, optional
        World direction of the map's top row (default +z).
    name : str, optional
        Label for metadata (e.g. the map's file name).
    """

    radiance_rgb: np.ndarray = 1.0
    radiance_map: np.ndarray | None = field(default=None, repr=False)
    n_directions: int = 256
    sampling: str = "stratified"
    seed: int = 0
    up: np.ndarray = (0.0, 0.0, 1.0)
    name: str = "environment"

    def __post_init__(self):
        what = "EnvironmentLight"
        object.__setattr__(self, "radiance_rgb", _rgb(self.radiance_rgb, what, "radiance_rgb", "W/(m² sr)"))
        object.__setattr__(self, "up", _unit(self.up, what, "up"))
        if isinstance(self.n_directions, bool) or not isinstance(self.n_directions, (int, np.integer)):
            raise InvalidParameterError(f"{what}: n_directions must be an integer, got {self.n_directions!r}.")
        if not 1 <= int(self.n_directions) <= MAX_DIRECTIONS:
            raise InvalidParameterError(
                f"{what}: n_directions must lie in [1, {MAX_DIRECTIONS}], got {self.n_directions}."
            )
        object.__setattr__(self, "n_directions", int(self.n_directions))
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise InvalidParameterError(f"{what}: seed must be an integer >= 0, got {self.seed!r}.")
        if self.sampling not in SAMPLING_METHODS:
            raise InvalidParameterError(
                f"{what}: sampling must be one of {', '.join(SAMPLING_METHODS)}, got {self.sampling!r}."
            )
        if self.radiance_map is not None:
            try:
                image = np.array(self.radiance_map, dtype=np.float64)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"{what}: radiance_map must be a numeric (H, W, 3) array.") from None
            if image.ndim != 3 or image.shape[2] != 3 or image.shape[0] < 1 or image.shape[1] < 1:
                raise InvalidParameterError(
                    f"{what}: radiance_map must have shape (H, W, 3) (an RGB equirectangular image), got {image.shape}."
                )
            if not np.all(np.isfinite(image)):
                raise InvalidParameterError(f"{what}: radiance_map contains NaN or infinite pixels.")
            if np.any(image < 0):
                raise InvalidParameterError(
                    f"{what}: radiance_map has negative pixels (min {image.min():g}); radiance must be >= 0."
                )
            image.setflags(write=False)
            object.__setattr__(self, "radiance_map", image)

    def to_dict(self) -> dict:
        """Plain description for metadata (a map is described by its name, shape and mean radiance)."""
        out = {
            "type": "environment",
            "name": self.name,
            "n_directions": self.n_directions,
            "sampling": self.sampling,
            "seed": self.seed,
            "up": self.up.tolist(),
        }
        if self.radiance_map is None:
            out["radiance_rgb_W_m2_sr"] = self.radiance_rgb.tolist()
        else:
            out["map_shape"] = list(self.radiance_map.shape)
            out["map_mean_radiance_rgb_W_m2_sr"] = self.radiance_map.reshape(-1, 3).mean(axis=0).tolist()
        return out

    def directional_samples(self) -> DirectionalSamples:
        """Expand the environment into ``n_directions`` directional samples (zero-weight ones dropped).

        Returns
        -------
        DirectionalSamples
            Directions toward the environment, irradiance weights ``E_k`` (W/m²) and solid angles.
        """
        rng = np.random.default_rng(self.seed)
        n = self.n_directions
        if self.radiance_map is None or self.sampling == "stratified":
            cos_theta, phi = _stratified_sphere(n, rng)
            solid_angle = np.full(n, 4.0 * np.pi / n)
            if self.radiance_map is None:
                radiance = np.broadcast_to(self.radiance_rgb, (n, 3))
            else:
                radiance = self._lookup(cos_theta, phi)
        else:
            cos_theta, phi, radiance, solid_angle = self._importance_samples(n, rng)
        sin_theta = np.sqrt(np.maximum(1.0 - cos_theta * cos_theta, 0.0))
        e1, e2 = _frame(self.up)
        directions = (
            (sin_theta * np.cos(phi))[:, None] * e1
            + (sin_theta * np.sin(phi))[:, None] * e2
            + cos_theta[:, None] * self.up
        )
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        irradiance = radiance * solid_angle[:, None]  # E_k = L dw
        keep = irradiance.max(axis=1) > 0.0
        return DirectionalSamples(directions[keep], irradiance[keep], solid_angle[keep])

    def _pixel_of(self, cos_theta, phi):
        h, w, _ = self.radiance_map.shape
        theta = np.arccos(np.clip(cos_theta, -1.0, 1.0))
        row = np.minimum((theta / np.pi * h).astype(np.int64), h - 1)
        col = np.minimum((np.mod(phi, 2.0 * np.pi) / (2.0 * np.pi) * w).astype(np.int64), w - 1)
        return row, col

    def _lookup(self, cos_theta, phi):
        row, col = self._pixel_of(cos_theta, phi)
        return self.radiance_map[row, col]

    def _importance_samples(self, n, rng):
        image = self.radiance_map
        h, w, _ = image.shape
        z_edges = np.cos(np.linspace(0.0, np.pi, h + 1))  # cos(theta) at the row boundaries
        pixel_solid_angle = (z_edges[:-1] - z_edges[1:]) * (2.0 * np.pi / w)  # dw of each row's pixels
        weight = (image @ LUMINANCE_WEIGHTS) * pixel_solid_angle[:, None]
        total = weight.sum()
        if not total > 0.0:
            return np.zeros(0), np.zeros(0), np.zeros((0, 3)), np.zeros(0)
        cdf = np.cumsum(weight.ravel()) / total
        u = (np.arange(n) + rng.random()) / n  # systematic (stratified) inversion of the CDF
        pixel = np.minimum(np.searchsorted(cdf, u, side="right"), h * w - 1)
        row, col = np.divmod(pixel, w)
        probability = weight.ravel()[pixel] / total
        cos_theta = z_edges[row] + (z_edges[row + 1] - z_edges[row]) * rng.random(n)  # uniform in dw
        phi = 2.0 * np.pi * (col + rng.random(n)) / w
        solid_angle = pixel_solid_angle[row] / (n * probability)  # 1 / (N pdf(w))
        return cos_theta, phi, image[row, col], solid_angle


def cosine_integral_error(samples: DirectionalSamples, n_normals: int = 2000, seed: int = 1) -> float:
    """Largest relative error of a sample set's estimate of ``int cos+ dw = pi`` over random normals.

    For a constant environment this is exactly the relative error of the irradiance on an unoccluded
    plane (``E = pi L``) that the samples give, maximised over ``n_normals`` uniformly random plane
    orientations; it states the sampling error of :meth:`EnvironmentLight.directional_samples`.

    Returns
    -------
    float
        ``max_n |sum_k dw_k max(n . w_k, 0) - pi| / pi``.
    """
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(n_normals, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    estimate = np.maximum(normals @ samples.directions.T, 0.0) @ samples.solid_angle
    return float(np.max(np.abs(estimate - np.pi)) / np.pi)


def as_light_list(lights) -> tuple:
    """One light or a sequence of lights as a tuple, checking that each is a light."""
    kinds = (DirectionalLight, PointLight, EnvironmentLight)
    if isinstance(lights, kinds):
        lights = (lights,)
    try:
        lights = tuple(lights)
    except TypeError:
        raise InvalidParameterError(
            f"lights must be a light or a sequence of lights, got {type(lights).__name__}."
        ) from None
    for light in lights:
        if not isinstance(light, kinds):
            raise InvalidParameterError(
                f"lights must be DirectionalLight, PointLight or EnvironmentLight objects, got {type(light).__name__}."
            )
    return lights
