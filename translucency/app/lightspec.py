"""Lights from the short text the command line's ``--light`` takes (:data:`LIGHT_SPEC_HELP`).

Parsing words a user types belongs to the application; :mod:`translucency.scatter.lights` keeps the
light records themselves, which validate their own values.
"""

from __future__ import annotations

from ..errors import InvalidParameterError
from ..scatter.lights import DirectionalLight, EnvironmentLight, PointLight

__all__ = ["LIGHT_SPEC_HELP", "parse_light_spec"]


LIGHT_SPEC_HELP = (
    "use 'x,y,z' (white directional light, E = 1 W/m^2), 'dir:x,y,z[:E or :r,g,b]', "
    "'point:x,y,z[:I or :r,g,b]' (position in mm, I in W/sr) or 'env:L or env:r,g,b[:N]' "
    "(constant radiance, N directions), several joined by ';'"
)


def _numbers(text: str, spec: str) -> list[float]:
    try:
        return [float(t) for t in text.split(",")]
    except ValueError:
        raise InvalidParameterError(f"light {spec!r}: {text!r} is not a list of numbers; {LIGHT_SPEC_HELP}.") from None


def parse_light_spec(text: str) -> tuple:
    """Lights from a short text (the CLI's ``--light``), e.g. ``"dir:0,0,1:3;point:0,0,200:0.5"``.

    ``x,y,z`` is a white directional light of 1 W/m²; ``dir:x,y,z[:E]``, ``point:x,y,z[:I]`` and
    ``env:L[:N]`` give the kind explicitly, with one number or ``r,g,b`` for ``E`` (W/m²), ``I`` (W/sr)
    or ``L`` (W/(m² sr)); several lights are joined by ``;``.

    Returns
    -------
    tuple of lights
    """
    if not isinstance(text, str) or not text.strip():
        raise InvalidParameterError(f"an empty light specification; {LIGHT_SPEC_HELP}.")
    lights = []
    for spec in (s.strip() for s in text.split(";")):
        if not spec:
            continue
        kind, _, rest = spec.partition(":")
        if not rest:
            kind, rest = "dir", spec
        parts = rest.split(":")
        kind = kind.strip().lower()
        if kind in ("dir", "directional", "point") and 1 <= len(parts) <= 2:
            vector = _numbers(parts[0], spec)
            value = _numbers(parts[1], spec) if len(parts) == 2 else [1.0]
            value = value[0] if len(value) == 1 else value
            if kind == "point":
                lights.append(PointLight(vector, value))
            else:
                lights.append(DirectionalLight(vector, value))
        elif kind in ("env", "environment") and 1 <= len(parts) <= 2:
            value = _numbers(parts[0], spec)
            value = value[0] if len(value) == 1 else value
            n = 256
            if len(parts) == 2:
                try:
                    n = int(parts[1])
                except ValueError:
                    raise InvalidParameterError(
                        f"light {spec!r}: the number of directions must be an integer; {LIGHT_SPEC_HELP}."
                    ) from None
            lights.append(EnvironmentLight(value, n_directions=n))
        else:
            raise InvalidParameterError(f"light {spec!r} is not understood; {LIGHT_SPEC_HELP}.")
    if not lights:
        raise InvalidParameterError(f"an empty light specification; {LIGHT_SPEC_HELP}.")
    return tuple(lights)
