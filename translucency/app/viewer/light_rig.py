"""The viewer's lights and the one its two angles steer: the first directional light, by azimuth and elevation.

:func:`light_direction` and :func:`light_angles` turn the two angles (degrees around ``up``) into a direction
and back; a :class:`LightRig` is the lights with their key light and its angles, and :meth:`LightRig.steered`
turns the key light. Directions are in the scan's own coordinates.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...errors import InvalidParameterError
from ..framing import DEFAULT_UP, frame_axes


def light_direction(azimuth, elevation, up=DEFAULT_UP) -> np.ndarray:
    """Unit direction toward a light at ``azimuth``, ``elevation`` (degrees) around ``up``.

    ``d = cos(e) (cos(a) e1 + sin(a) e2) + sin(e) up``: elevation is the angle above the plane
    perpendicular to ``up``; azimuth 0 is the world +z made perpendicular to ``up`` (+x when ``up`` is
    along z) and 90 is ``up x`` that (+x for ``up`` = +y).
    """
    up, e1, e2 = frame_axes(up)
    a, e = math.radians(azimuth), math.radians(elevation)
    return math.cos(e) * (math.cos(a) * e1 + math.sin(a) * e2) + math.sin(e) * up


def light_angles(direction, up=DEFAULT_UP) -> tuple[float, float]:
    """``(azimuth, elevation)`` in degrees of a direction (inverse of :func:`light_direction`)."""
    up, e1, e2 = frame_axes(up)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    elevation = math.degrees(math.asin(float(np.clip(d @ up, -1.0, 1.0))))
    azimuth = math.degrees(math.atan2(float(d @ e2), float(d @ e1)))
    return azimuth, elevation


@dataclasses.dataclass(eq=False)
class LightRig:
    """The lights and the key light the two angles steer.

    Attributes
    ----------
    lights : tuple of lights
        Every light, directions in the scan's coordinates.
    key : int or None
        Index in ``lights`` of the first directional light, the one the angles steer (None: there is none).
    azimuth, elevation : float or None
        The key light's angles, degrees around the viewer's ``up`` (None without a key light).
    """

    lights: tuple
    key: int | None
    azimuth: float | None
    elevation: float | None

    @classmethod
    def of(cls, lights, up) -> LightRig:
        """The rig of ``lights`` (a light or a sequence): its first directional light is the key, with its
        angles around ``up``."""
        from ...scatter.lights import DirectionalLight, as_light_list

        lights = as_light_list(lights)
        key = next((i for i, light in enumerate(lights) if isinstance(light, DirectionalLight)), None)
        angles = light_angles(lights[key].direction, up) if key is not None else (None, None)
        return cls(lights, key, *angles)

    def steered(self, azimuth, elevation, up) -> LightRig | None:
        """The rig with the key light toward :func:`light_direction` of ``azimuth``, ``elevation`` (degrees around
        ``up``; finite, elevation in [-90, 90]); its irradiance stays. None when those are its angles already; a
        sentence when there is no key light."""
        from ...scatter.lights import DirectionalLight

        if self.key is None:
            raise InvalidParameterError("the lights hold no directional light to steer; add one (--light-dir X,Y,Z).")
        azimuth, elevation = float(azimuth), float(elevation)
        if not (np.isfinite(azimuth) and np.isfinite(elevation) and -90.0 <= elevation <= 90.0):
            raise InvalidParameterError(
                f"light angles must be finite with elevation in [-90, 90] degrees, "
                f"got azimuth {azimuth!r}, elevation {elevation!r}."
            )
        if (azimuth, elevation) == (self.azimuth, self.elevation):
            return None
        lights = list(self.lights)
        lights[self.key] = DirectionalLight(light_direction(azimuth, elevation, up), lights[self.key].irradiance_rgb)
        return LightRig(tuple(lights), self.key, azimuth, elevation)

    def holds(self, lights) -> bool:
        """Whether ``lights`` (a sequence) are this rig's lights, light for light."""
        return [light.to_dict() for light in lights] == [light.to_dict() for light in self.lights]
