"""An environment light from a map file: :mod:`translucency.io.envmap` reads it, the light record is scatter's."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.envmap import EnvironmentMapError, read_equirectangular
from ..scatter.lights import EnvironmentLight

__all__ = ["load_environment"]


def load_environment(
    path,
    *,
    n_directions: int = 256,
    sampling: str = "importance",
    seed: int = 0,
    up=(0.0, 0.0, 1.0),
    scale: float = 1.0,
) -> EnvironmentLight:
    """An :class:`~translucency.scatter.lights.EnvironmentLight` from an equirectangular map file.

    Parameters
    ----------
    path : str or os.PathLike
        The map (see :func:`translucency.io.envmap.read_equirectangular`).
    n_directions, sampling, seed, up
        As in :class:`~translucency.scatter.lights.EnvironmentLight` (importance sampling by default:
        real maps have small bright regions such as the sun).
    scale : float, optional
        Factor turning pixel values into W/(m² sr).
    """
    if not (np.isfinite(scale) and scale >= 0):
        raise EnvironmentMapError(f"scale must be a finite number >= 0, got {scale!r}.")
    radiance = read_equirectangular(path) * float(scale)
    return EnvironmentLight(
        radiance_map=radiance, n_directions=n_directions, sampling=sampling, seed=seed, up=up, name=Path(path).name
    )
