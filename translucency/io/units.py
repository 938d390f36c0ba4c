"""Length units of mesh files: parsing, conversion to mm, and the plausibility check of a scan's size.

Scan files rarely state their unit. translucency works in mm (scattering coefficients are in 1/mm),
so every mesh is converted on entry with a factor ``mm_per_unit``. A wrong unit does not fail, it
silently makes the object 1000 times too small or too large for the material, so a scan whose size
is implausible for the given unit gets an :class:`ImplausibleSizeWarning` that names the unit that
would make it plausible, and a size no object can have is an error.

When no unit is given it is inferred from the size (:func:`infer_unit`), by this rule: the file is
read in **millimetres** when its largest bounding-box side is 5 to 5000 units (an object of 5 mm to
5 m), and in **metres** when it is 0.005 to 5 units (again 5 mm to 5 m). Those are the two units scan
files come in: millimetres from photogrammetry, CAD and 3D printing, metres from scanning
repositories and glTF (whose unit is the metre). Between the two the switch sits at 5 units, where
both readings are equally far (in log scale) from a typical 160 mm object; centimetres and inches are
never inferred, as their sizes overlap those of the two others (pass them). A file outside 0.005 to
5000 units is plausible in no unit and is refused with a sentence; the shared scans come out at
their real size (those of scanning repositories from metres, the photogrammetry ones from
millimetres). The choice is said in one line (:class:`UnitInferredWarning`) and recorded
(:attr:`TriangleMesh.unit_inferred <translucency.geometry.mesh.TriangleMesh.unit_inferred>`).

================ ========================================================== =====
name             meaning                                                    unit
================ ========================================================== =====
mm_per_unit      length of one file unit                                    mm
extent           largest side of the bounding box                           mm
PLAUSIBLE_EXTENT extents of scanned objects: 5 mm (a ring) to 5 m (a car)   mm
ABSURD_EXTENT    outside this range the file cannot be a scan at all        mm
================ ========================================================== =====

Outputs record their units with :func:`unit_metadata` (``length_unit`` = ``"mm"``, the coordinates'
unit, and ``source_unit`` ... for the scan file's) and :data:`RADIANCE_UNIT` /
:data:`INCIDENT_FLUX_UNIT` for the values computed on them.
"""

from __future__ import annotations

import math
import numbers

from ..errors import InvalidParameterError, MeshError, option, warn_user

__all__ = [
    "UNITS",
    "LENGTH_UNIT",
    "RADIANCE_UNIT",
    "INCIDENT_FLUX_UNIT",
    "PLAUSIBLE_EXTENT",
    "ABSURD_EXTENT",
    "ImplausibleSizeWarning",
    "UnitInferredWarning",
    "parse_unit",
    "unit_label",
    "unit_words",
    "likely_unit",
    "infer_unit",
    "inferred_unit_message",
    "unit_metadata",
    "implausible_size_message",
    "check_extent",
]

#: Unit of every length translucency computes and writes (coordinates of bakes, edge lengths, extents).
LENGTH_UNIT = "mm"

#: Unit of the radiance and of ``B`` in every output: the solver's answer for lights whose irradiance
#: (directional, on a surface facing the light) is given in W/m^2, so per W/m^2 of that irradiance.
RADIANCE_UNIT = "W/(m^2 sr) per W/m^2 of irradiance of the light"

#: Unit of the incident flux density entering the surface, ``phi = T12 E cos V`` (the solver's input).
INCIDENT_FLUX_UNIT = "W/m^2"

#: Millimetres per unit of the named length units.
UNITS: dict[str, float] = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4}

_UNIT_WORDS = {"mm": "millimetres", "cm": "centimetres", "m": "metres", "in": "inches"}

#: Extents (largest bounding-box side, mm) of real scanned objects; outside it a warning is given.
PLAUSIBLE_EXTENT = (5.0, 5000.0)

#: Extents (mm) no scan can have (1 nm to 1000 km); outside it loading fails.
ABSURD_EXTENT = (1e-6, 1e9)


#: Units :func:`infer_unit` chooses from, tried in this order.
INFERRED_UNITS = ("mm", "m")


class ImplausibleSizeWarning(UserWarning):
    """A mesh whose size is implausible for its length unit (probably the wrong unit was given)."""


class UnitInferredWarning(UserWarning):
    """No unit was given and one was inferred from the size: the line that says which, and how to override it."""


def parse_unit(unit: str | float) -> float:
    """Return the length of one unit in mm.

    Parameters
    ----------
    unit : {"mm", "cm", "m", "in"} or float
        A unit name (case-insensitive) or a positive number of mm per unit (a number in a string,
        such as ``"2.5"``, is accepted too, for command lines).

    Returns
    -------
    float
        Millimetres per unit.

    Raises
    ------
    InvalidParameterError
        For an unknown name or a number that is not positive and finite.
    """
    if isinstance(unit, str):
        key = unit.strip().lower()
        if key in UNITS:
            return UNITS[key]
        try:
            value = float(key)
        except ValueError:
            raise InvalidParameterError(
                f"unknown length unit {unit!r}; use one of {', '.join(UNITS)} or a number of mm per unit."
            ) from None
    elif isinstance(unit, numbers.Real) and not isinstance(unit, bool):
        value = float(unit)
    else:
        raise InvalidParameterError(
            f"the length unit must be one of {', '.join(UNITS)} or a number of mm per unit, not {unit!r}."
        )
    if not (math.isfinite(value) and value > 0):
        raise InvalidParameterError(
            f"the length unit {unit!r} is not a positive number of mm per unit; pass e.g. 1 or 'mm'."
        )
    return value


def unit_label(mm_per_unit: float) -> str:
    """Return ``"mm"``, ``"cm"``, ``"m"`` or ``"in"`` for a known factor, else ``"<factor> mm"``."""
    for name, factor in UNITS.items():
        if math.isclose(mm_per_unit, factor, rel_tol=1e-12):
            return name
    return f"{mm_per_unit:g} mm"


def unit_words(mm_per_unit: float) -> str:
    """The unit in words (``"metres"``, ``"millimetres"``, ...), or ``"units of <factor> mm"``."""
    label = unit_label(mm_per_unit)
    return _UNIT_WORDS.get(label, f"units of {label}")


def infer_unit(extent_in_file_units: float, name: str = "the mesh") -> str:
    """The unit of a file that states none, from its size (the rule is in the module docstring).

    Parameters
    ----------
    extent_in_file_units : float
        Largest bounding-box side in the file's own unit.
    name : str
        How the sentence names the mesh.

    Returns
    -------
    str
        ``"mm"`` for 5 to 5000 units, ``"m"`` for 0.005 to 5 units (an object of 5 mm to 5 m).

    Raises
    ------
    MeshError
        When no unit makes the size plausible (outside 0.005 to 5000 units), or the size is zero or
        not finite.
    """
    low, high = PLAUSIBLE_EXTENT
    for unit in INFERRED_UNITS:
        if low <= extent_in_file_units * UNITS[unit] <= high:
            return unit
    smallest, largest = min(UNITS[u] for u in INFERRED_UNITS), max(UNITS[u] for u in INFERRED_UNITS)
    finite = math.isfinite(extent_in_file_units) and extent_in_file_units > 0
    if not finite or extent_in_file_units * smallest > ABSURD_EXTENT[1]:
        check_extent(extent_in_file_units * smallest, smallest, name)  # its own sentence: zero, not finite, huge
    if extent_in_file_units * largest < ABSURD_EXTENT[0]:
        check_extent(extent_in_file_units * largest, largest, name)  # its own sentence: too small for any object
    readings = ", ".join(
        f"as {_UNIT_WORDS[unit]} {_size(extent_in_file_units * UNITS[unit])}" for unit in INFERRED_UNITS
    )
    raise MeshError(
        f"{name} is {extent_in_file_units:.3g} units across and no {option('unit')} was given, but no unit makes "
        f"that a plausible scan of 5 mm to 5 m ({readings}); pass {option('unit')} with the file's unit "
        "(mm, cm, m, in or a number of mm per unit)."
    )


def inferred_unit_message(name: str, extent_in_file_units: float, unit: str) -> str:
    """The line that says which unit was inferred: ``"bunny.ply: no --unit given; 0.156 units across,
    read as metres (156 mm); pass --unit to override"`` (``unit=`` in a Python call)."""
    factor = UNITS[unit]
    return (
        f"{name}: no {option('unit')} given; {extent_in_file_units:.3g} units across, read as "
        f"{_UNIT_WORDS[unit]} ({_size(extent_in_file_units * factor)}); pass {option('unit')} to override"
    )


def unit_metadata(mm_per_unit: float, inferred: bool = False) -> dict:
    """How every output records its units: ``length_unit`` (always ``"mm"``, the unit of the coordinates
    written) and the unit of the scan file the mesh was read from, ``source_unit`` (label),
    ``source_unit_name`` (in words), ``source_mm_per_unit`` (mm) and ``source_unit_inferred`` (True when
    it was inferred from the size).

    The file's unit is named ``source_...`` so that nobody reads ``source_unit = "m"`` as the unit of
    the coordinates of the output, which are in mm whatever the file's unit was.
    """
    return {
        "length_unit": LENGTH_UNIT,
        "source_unit": unit_label(mm_per_unit),
        "source_unit_name": unit_words(mm_per_unit),
        "source_mm_per_unit": float(mm_per_unit),
        "source_unit_inferred": bool(inferred),
    }


def _size(extent_mm: float) -> str:
    """A length in mm for a sentence: ``"156 mm"``, ``"0.16 mm"``, ``"1.5e+05 mm"``."""
    return f"{extent_mm:.2g} mm" if extent_mm < 1 else f"{float(f'{extent_mm:.3g}'):g} mm"


def likely_unit(extent_in_file_units: float) -> str | None:
    """Name the unit that makes a file extent most plausible for a scanned object.

    Parameters
    ----------
    extent_in_file_units : float
        Largest bounding-box side in the file's own (unknown) unit.

    Returns
    -------
    str or None
        The unit of :data:`UNITS` whose extent in mm lies in :data:`PLAUSIBLE_EXTENT`, closest (in
        log scale) to the middle of that range; None when no unit makes it plausible.
    """
    low, high = PLAUSIBLE_EXTENT
    middle = math.sqrt(low * high)
    best, best_distance = None, math.inf
    for name, factor in UNITS.items():
        extent_mm = extent_in_file_units * factor
        if low <= extent_mm <= high:
            distance = abs(math.log(extent_mm / middle))
            if distance < best_distance:
                best, best_distance = name, distance
    return best


def implausible_size_message(extent_mm: float, mm_per_unit: float, name: str = "the mesh") -> str | None:
    """Return the warning sentence for an implausible size, or None when the size is plausible.

    Parameters
    ----------
    extent_mm : float
        Largest bounding-box side after conversion, in mm.
    mm_per_unit : float
        The factor that was used.
    name : str
        How the sentence names the mesh.
    """
    low, high = PLAUSIBLE_EXTENT
    if low <= extent_mm <= high:
        return None
    suggestion = likely_unit(extent_mm / mm_per_unit)
    size = f"{extent_mm:.2g} mm" if extent_mm < 1 else f"{extent_mm:.4g} mm"
    if suggestion is not None and not math.isclose(UNITS[suggestion], mm_per_unit):
        return (
            f"{name} is {size} across, implausible for a scan in {unit_label(mm_per_unit)}; "
            f"if the file is in {_UNIT_WORDS[suggestion]} pass {option('unit', suggestion)}."
        )
    return (
        f"{name} is {size} across, implausible for a scanned object (5 mm to 5 m); "
        f"check the file's unit and pass it as {option('unit')} (a name or mm per unit)."
    )


def check_extent(extent_mm: float, mm_per_unit: float, name: str = "the mesh") -> None:
    """Raise for an absurd size, warn for an implausible one, else do nothing.

    Parameters
    ----------
    extent_mm : float
        Largest bounding-box side in mm.
    mm_per_unit : float
        The unit factor that was applied, in mm per file unit.
    name : str
        How the sentences name the mesh.

    Raises
    ------
    MeshError
        When the extent is zero, not finite, or outside :data:`ABSURD_EXTENT`.

    Warns
    -----
    ImplausibleSizeWarning
        When the extent is outside :data:`PLAUSIBLE_EXTENT`.
    """
    low, high = ABSURD_EXTENT
    if not math.isfinite(extent_mm) or extent_mm > high:
        raise MeshError(
            f"{name} is {extent_mm:.3g} mm across, larger than any scanned object; "
            "check the file's coordinates and unit."
        )
    if extent_mm < low:
        if extent_mm == 0:
            raise MeshError(
                f"{name} has all its vertices at one position (size 0); the file holds no surface, export it again."
            )
        raise MeshError(
            f"{name} is {extent_mm:.3g} mm across, smaller than any scanned object; check the file's "
            "coordinates and unit."
        )
    message = implausible_size_message(extent_mm, mm_per_unit, name)
    if message is not None:
        warn_user(message, ImplausibleSizeWarning)
