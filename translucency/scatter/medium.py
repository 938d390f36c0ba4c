"""Optical coefficients of a homogeneous scattering medium and the quantities derived from them.

A :class:`Medium` holds, per colour channel, the absorption and scattering coefficients, the
Henyey-Greenstein mean cosine and the relative index of refraction, validated once. The derived
quantities of the diffusion models (docs/physics.md §2.1) are small pure functions on arrays, used both
by :class:`Medium` and by the reference formulas in :mod:`translucency.scatter.dipoles`.

=============== ======================================================== =====
symbol          meaning                                                  unit
=============== ======================================================== =====
sigma_a         absorption coefficient                                   1/mm
sigma_s         scattering coefficient                                   1/mm
g               Henyey-Greenstein mean cosine of the phase function      1
eta             relative index of refraction n_inside / n_outside        1
sigma_s_reduced reduced scattering sigma_s (1 - g)                       1/mm
sigma_t         extinction sigma_s + sigma_a (unreduced)                 1/mm
sigma_t_reduced reduced extinction sigma_s' + sigma_a                    1/mm
alpha_reduced   reduced albedo sigma_s' / sigma_t'                       1
D               diffusion coefficient 1 / (3 sigma_t')                   mm
sigma_tr        effective transport coefficient sqrt(sigma_a / D)        1/mm
d_e             extrapolation distance 2.131 D / sqrt(alpha')            mm
A               boundary reflection parameter (fresnel.py)               1
=============== ======================================================== =====
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidParameterError
from . import fresnel

__all__ = [
    "DEFAULT_ETA",
    "Medium",
    "validate_coefficients",
    "sigma_s_reduced",
    "sigma_t",
    "sigma_t_reduced",
    "alpha_reduced",
    "diffusion_coefficient",
    "sigma_tr",
    "extrapolation_distance",
]

CHANNELS = ("red", "green", "blue")
#: Relative index of refraction of the catalogue's materials unless their table gives another.
DEFAULT_ETA = 1.3


def sigma_s_reduced(sigma_s, g):
    """Reduced scattering coefficient ``sigma_s' = sigma_s (1 - g)`` in 1/mm (docs/physics.md §2.1, §2.3)."""
    return np.asarray(sigma_s, dtype=np.float64) * (1.0 - np.asarray(g, dtype=np.float64))


def sigma_t(sigma_a, sigma_s):
    """Unreduced extinction coefficient ``sigma_t = sigma_s + sigma_a`` in 1/mm (docs/physics.md §2.1)."""
    return np.asarray(sigma_s, dtype=np.float64) + np.asarray(sigma_a, dtype=np.float64)


def sigma_t_reduced(sigma_a, sigma_s, g):
    """Reduced extinction coefficient ``sigma_t' = sigma_s (1 - g) + sigma_a`` in 1/mm (docs/physics.md §2.1)."""
    return sigma_s_reduced(sigma_s, g) + np.asarray(sigma_a, dtype=np.float64)


def alpha_reduced(sigma_a, sigma_s, g):
    """Reduced albedo ``alpha' = sigma_s' / sigma_t'`` (dimensionless, docs/physics.md §2.1)."""
    return sigma_s_reduced(sigma_s, g) / sigma_t_reduced(sigma_a, sigma_s, g)


def diffusion_coefficient(sigma_a, sigma_s, g):
    """Classical diffusion coefficient ``D = 1 / (3 sigma_t')`` in mm (docs/physics.md §2.1)."""
    return 1.0 / (3.0 * sigma_t_reduced(sigma_a, sigma_s, g))


def sigma_tr(sigma_a, sigma_s, g):
    """Effective transport coefficient ``sigma_tr = sqrt(3 sigma_a sigma_t')`` in 1/mm (docs/physics.md §2.1)."""
    return np.sqrt(3.0 * np.asarray(sigma_a, dtype=np.float64) * sigma_t_reduced(sigma_a, sigma_s, g))


def extrapolation_distance(sigma_a, sigma_s, g):
    """Extrapolation distance ``d_e = 2.131 D / sqrt(alpha')`` in mm (docs/physics.md §2.1; FHK14 eq. 21)."""
    return 2.131 * diffusion_coefficient(sigma_a, sigma_s, g) / np.sqrt(alpha_reduced(sigma_a, sigma_s, g))


#: The largest sigma_a or sigma_s (1/mm) a medium may have: a mean free path of a femtometre, far below an atom's
#: size (1e-7 mm). Far beyond it the model's arithmetic overflows (at about 1e150/mm).
MAX_COEFFICIENT_PER_MM = 1e12
#: The smallest reduced scattering coefficient sigma_s (1 - g) (1/mm): a reduced scattering length of 1e17 km,
#: beyond any object. Below it the model's arithmetic under- and overflows (at about 1e-300/mm).
MIN_REDUCED_SCATTERING_PER_MM = 1e-20


def check_eta(eta, what: str = "") -> None:
    """Refuse a relative index of refraction (a number or an array) that is not finite or lies outside
    [1, :data:`~translucency.scatter.fresnel.ETA_MAX`], in one sentence (starting with ``what``, when given)."""
    lead = f"{what}: " if what else ""
    try:
        e = np.asarray(eta, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{lead}eta must be a number, got {eta!r}.") from None
    if not np.all(np.isfinite(e)):
        raise InvalidParameterError(f"{lead}eta must be finite, got {e.tolist()}.")
    if np.any(e < 1):
        raise InvalidParameterError(
            f"{lead}eta = n_inside / n_outside must be >= 1, got {e.tolist()}; "
            "the diffusion models assume light enters an optically denser medium."
        )
    if np.any(e > fresnel.ETA_MAX):
        raise InvalidParameterError(
            f"{lead}eta = n_inside / n_outside must be at most {fresnel.ETA_MAX}, got {e.tolist()}; "
            "the Fresnel moment fits of the diffusion models hold from 1 to that value (docs/physics.md §3.3)."
        )


def validate_coefficients(sigma_a, sigma_s, g, eta, *, what: str = "medium"):
    """Check optical coefficients and return them as broadcast float64 arrays.

    Raises :class:`~translucency.errors.InvalidParameterError` with a sentence naming the problem:
    non-finite values, ``sigma_a < 0``, ``sigma_s < 0``, ``g`` outside (-1, 1), ``eta`` outside
    [1, :data:`~translucency.scatter.fresnel.ETA_MAX`], or no
    scattering at all (``alpha' = 0``: the diffusion models need ``sigma_s (1 - g) > 0``).

    Returns
    -------
    tuple of ndarray
        ``(sigma_a, sigma_s, g, eta)`` broadcast to a common shape, float64.
    """
    names = ("sigma_a", "sigma_s", "g", "eta")
    try:
        arrays = [np.asarray(v, dtype=np.float64) for v in (sigma_a, sigma_s, g, eta)]
        arrays = np.broadcast_arrays(*arrays)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            f"{what}: sigma_a, sigma_s, g and eta must be numbers or arrays of matching shape ({exc})."
        ) from None
    for name, value in zip(names, arrays):
        if not np.all(np.isfinite(value)):
            raise InvalidParameterError(f"{what}: {name} must be finite, got {value.tolist()}.")
    a, s, gg, e = arrays
    if np.any(a < 0):
        raise InvalidParameterError(f"{what}: sigma_a must be >= 0 (1/mm), got {a.tolist()}.")
    if np.any(s < 0):
        raise InvalidParameterError(f"{what}: sigma_s must be >= 0 (1/mm), got {s.tolist()}.")
    if np.any((gg <= -1) | (gg >= 1)):
        raise InvalidParameterError(f"{what}: g must lie in (-1, 1), got {gg.tolist()}.")
    check_eta(e, what)
    for name, value in (("sigma_a", a), ("sigma_s", s)):
        if np.any(value > MAX_COEFFICIENT_PER_MM):
            largest = f"1e{round(math.log10(MAX_COEFFICIENT_PER_MM))}"
            raise InvalidParameterError(
                f"{what}: {name} = {value.max():g}/mm is beyond any material (a mean free path of "
                f"{1 / value.max():.2g} mm, far below an atom's size); give coefficients in 1/mm, at most {largest}."
            )
    if np.any((s * (1 - gg) > 0) & (s * (1 - gg) < MIN_REDUCED_SCATTERING_PER_MM)):
        raise InvalidParameterError(
            f"{what}: the medium scatters too little for any diffuse light (sigma_s (1 - g) = "
            f"{(s * (1 - gg)).min():.2g}/mm, a reduced scattering length of {1 / (s * (1 - gg)).min():.2g} mm); give "
            f"sigma_s (1 - g) of at least {MIN_REDUCED_SCATTERING_PER_MM:.0e}/mm."
        )
    if np.any(s * (1 - gg) <= 0):
        raise InvalidParameterError(
            f"{what}: the medium must scatter (sigma_s (1 - g) > 0), got sigma_s = {s.tolist()}, "
            f"g = {gg.tolist()}; a purely absorbing medium has no diffuse subsurface light."
        )
    return a.copy(), s.copy(), gg.copy(), e.copy()


@dataclass(frozen=True)
class Medium:
    """A homogeneous medium with one set of coefficients per colour channel (float64, 1/mm).

    Build it from unreduced coefficients ``Medium(sigma_a, sigma_s, g, eta)`` or from reduced ones
    with :meth:`from_reduced` (``g = 0``). Scalars broadcast to the three RGB channels. Derived
    quantities (docs/physics.md §2.1) are available as properties.

    Parameters
    ----------
    sigma_a, sigma_s : array_like
        Absorption and scattering coefficients, 1/mm, per channel.
    g : array_like
        Henyey-Greenstein mean cosine, per channel, in (-1, 1).
    eta : float
        Relative index of refraction ``n_inside / n_outside`` (>= 1), shared by the channels.
    name : str, optional
        A label (the catalogue name for presets).
    """

    sigma_a: np.ndarray
    sigma_s: np.ndarray
    g: np.ndarray = field(default_factory=lambda: np.zeros(3))
    eta: float = DEFAULT_ETA
    name: str = "custom"

    def __post_init__(self):
        if np.ndim(self.eta) != 0:
            raise InvalidParameterError(f"{self.name}: eta must be a single number, got {self.eta!r}.")
        a, s, g, eta = validate_coefficients(self.sigma_a, self.sigma_s, self.g, self.eta, what=self.name)
        if a.ndim == 0:
            a, s, g = (np.full(3, float(v)) for v in (a, s, g))
        elif a.ndim != 1:
            raise InvalidParameterError(
                f"{self.name}: coefficients must be one number or one number per channel, got shape {a.shape}."
            )
        for value in (a, s, g):
            value.setflags(write=False)
        object.__setattr__(self, "sigma_a", a)
        object.__setattr__(self, "sigma_s", s)
        object.__setattr__(self, "g", g)
        object.__setattr__(self, "eta", float(eta.flat[0]))

    @classmethod
    def from_reduced(cls, sigma_a, sigma_s_reduced, eta: float = DEFAULT_ETA, name: str = "custom") -> Medium:
        """A medium from reduced scattering coefficients ``sigma_s'`` (1/mm) with ``g = 0``."""
        return cls(sigma_a, sigma_s_reduced, np.zeros(np.shape(sigma_s_reduced)), eta, name)

    @property
    def n_channels(self) -> int:
        """Number of colour channels (3 for RGB)."""
        return int(self.sigma_a.shape[0])

    @property
    def sigma_s_reduced(self) -> np.ndarray:
        """Reduced scattering ``sigma_s (1 - g)``, 1/mm."""
        return sigma_s_reduced(self.sigma_s, self.g)

    @property
    def sigma_t(self) -> np.ndarray:
        """Unreduced extinction ``sigma_s + sigma_a``, 1/mm."""
        return sigma_t(self.sigma_a, self.sigma_s)

    @property
    def sigma_t_reduced(self) -> np.ndarray:
        """Reduced extinction ``sigma_s' + sigma_a``, 1/mm."""
        return sigma_t_reduced(self.sigma_a, self.sigma_s, self.g)

    @property
    def alpha_reduced(self) -> np.ndarray:
        """Reduced albedo ``sigma_s' / sigma_t'``."""
        return alpha_reduced(self.sigma_a, self.sigma_s, self.g)

    @property
    def D(self) -> np.ndarray:
        """Diffusion coefficient ``1 / (3 sigma_t')``, mm."""
        return diffusion_coefficient(self.sigma_a, self.sigma_s, self.g)

    @property
    def sigma_tr(self) -> np.ndarray:
        """Effective transport coefficient ``sqrt(3 sigma_a sigma_t')``, 1/mm."""
        return sigma_tr(self.sigma_a, self.sigma_s, self.g)

    @property
    def d_e(self) -> np.ndarray:
        """Extrapolation distance ``2.131 D / sqrt(alpha')``, mm."""
        return extrapolation_distance(self.sigma_a, self.sigma_s, self.g)

    @property
    def A(self) -> float:
        """Boundary reflection parameter ``(1 - C_E(eta)) / (2 C_phi(eta))``."""
        return float(fresnel.reflection_parameter_A(self.eta))

    @property
    def mean_free_path(self) -> np.ndarray:
        """Reduced mean free path ``1 / sigma_t'``, mm."""
        return 1.0 / self.sigma_t_reduced

    @property
    def diffusion_length(self) -> np.ndarray:
        """Diffusion length ``1 / sigma_tr``, mm (infinite where ``sigma_a = 0``)."""
        with np.errstate(divide="ignore"):
            return 1.0 / self.sigma_tr

    def scaled(self, factor: float) -> Medium:
        """The same material with every coefficient multiplied by ``factor`` (e.g. a unit change)."""
        if not (np.isfinite(factor) and factor > 0):
            raise InvalidParameterError(f"{self.name}: a coefficient scale must be a positive number, got {factor!r}.")
        return Medium(self.sigma_a * factor, self.sigma_s * factor, self.g, self.eta, self.name)

    def describe(self) -> dict:
        """Coefficients and derived quantities as plain lists and numbers (for metadata and tables)."""
        return {
            "name": self.name,
            "eta": self.eta,
            "sigma_a_per_mm": self.sigma_a.tolist(),
            "sigma_s_per_mm": self.sigma_s.tolist(),
            "g": self.g.tolist(),
            "sigma_s_reduced_per_mm": self.sigma_s_reduced.tolist(),
            "alpha_reduced": self.alpha_reduced.tolist(),
            "mean_free_path_mm": self.mean_free_path.tolist(),
            "diffusion_length_mm": self.diffusion_length.tolist(),
        }
