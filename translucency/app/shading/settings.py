"""The shading settings: every choice a solve takes, its default, unit, check and help text, written once.

:class:`ShadeSettings` is the one record the command line (:mod:`translucency.app.options`), the viewer,
batch baking (:class:`~translucency.app.bake.BakeSettings` adds the files' unit and the lights) and
``compare`` build and pass down; it is validated on construction, with one sentence that names the setting
as the user wrote it (``--tol`` on the command line, ``tol`` in Python). Each field is declared once, with
its help text and unit (:func:`_setting`); from that one declaration come the parser's ``--help``
(:data:`HELP`), the table below and the entry points' docstrings (:func:`settings_table`), and the bake's
metadata records the same fields. The model and method names and their checks are
:mod:`translucency.scatter.names`'; the shading policy's own defaults (the time limit, the default light)
are here.

An entry point takes ``settings=`` and may take keyword shortcuts for single fields, forwarded by
:func:`settings_with` without declaring a default of its own.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import KW_ONLY, dataclass
from pathlib import Path

import numpy as np

from ...errors import InvalidParameterError, setting_name
from ...scatter.names import (
    DEFAULT_BOUNCES,
    DEFAULT_DEVICE,
    DEFAULT_METHOD,
    DEFAULT_MODEL,
    DEFAULT_TOL,
    MAX_BOUNCES,
    check_bounces,
    check_device,
    check_method,
    check_model,
    check_tol,
)

__all__ = [
    "ShadeSettings",
    "HELP",
    "DEFAULT_MATERIAL",
    "DEFAULT_TIME_LIMIT_S",
    "DEFAULT_LIGHT_DIRECTION",
    "VIEWER_METHOD",
    "VIEWER_TOL",
    "viewer_settings",
    "RESOLUTIONS",
    "ALBEDO_SOURCES",
    "default_light_direction",
    "parse_resolution",
    "resolve_medium",
    "settings_with",
    "settings_table",
]

DEFAULT_MATERIAL = "marble"
#: Seconds a light's solve (its bounces included) may take by its estimate unless told otherwise (``time_limit``).
DEFAULT_TIME_LIMIT_S = 300.0
#: From the object toward the default light, in the display frame (right, up, front; see
#: :func:`translucency.io.upright.display_frame`): above, in front and a little to the right. For a
#: scan whose up is +y (the default bunny) this is the direction in the scan's own coordinates too.
DEFAULT_LIGHT_DIRECTION = (0.35, 1.0, 0.45)
#: The viewer's own method and tolerance: relighting operators (docs/physics.md §8.7), prepared once per material,
#: model and tolerance on every vertex, then a new light is one pass over them, at the default tolerance (a proxy
#: where the operators would not fit the memory budget); their size and speed against the tolerance are in
#: bench/README.md, "Relighting".
VIEWER_METHOD = "relight"
VIEWER_TOL = DEFAULT_TOL


#: The named resolutions (besides a proxy edge length in mm).
RESOLUTIONS = ("full", "auto")
#: Where the albedo comes from: the material's own, or the scan's colour per vertex read as its diffuse
#: reflectance with the material's mean free path (docs/physics.md §6.5).
ALBEDO_SOURCES = ("material", "vertex_colors")


def _setting(default, unit: str, help: str, flag: str | None = None):
    """A field of :class:`ShadeSettings`: its default, its unit and its help text (``%%`` for a per cent
    sign, as argparse reads it), declared once; ``flag`` is the command line's help where its option reads
    otherwise (a flag that switches the setting, or values only Python can pass left out)."""
    return dataclasses.field(default=default, metadata={"unit": unit, "help": help, "flag": flag or help})


def default_light_direction(up: str = "+y") -> np.ndarray:
    """Direction (unit-free, scan coordinates) from the object toward the default light for an up axis.

    :data:`DEFAULT_LIGHT_DIRECTION` turned from the display frame into the scan's frame: above the
    scan along ``up`` (``"+x"`` ... ``"-z"``) and in front of it.
    """
    from ...io.upright import to_scan_frame

    return to_scan_frame(DEFAULT_LIGHT_DIRECTION, up)


def _positive(value) -> bool:
    """True for a finite real number > 0 (not a bool)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value) and value > 0


def parse_resolution(value):
    """``"full"``, ``"auto"`` or a proxy edge length in mm (a positive number, or text of one), checked."""
    if value in RESOLUTIONS:
        return value
    edge = value
    if isinstance(value, str):
        try:
            edge = float(value)
        except ValueError:
            edge = None
    if not _positive(edge):
        raise InvalidParameterError(
            f"{setting_name('resolution')} must be full, auto or a proxy edge length in mm, got {value!r}."
        )
    return float(edge)


@dataclass(frozen=True)
class ShadeSettings:
    """Every setting of a solve, validated on construction and built by keyword; the fields, their units and
    defaults are written once, in their declarations, and listed below; every field but the material is given by
    name. ``material`` is stored as a
    :class:`~translucency.scatter.medium.Medium`, ``up`` as ``"+x"`` ... ``"-z"`` or ``"auto"``."""

    material: object = _setting(
        DEFAULT_MATERIAL,
        "1/mm",
        "catalogue name (see 'translucency materials'), a material file (.toml or .json), a catalogue entry or "
        "a Medium",
        flag="catalogue name (see 'translucency materials') or a material file, .toml or .json",
    )
    _: KW_ONLY  # the material may be given by position, every other field by name
    model: str = _setting(
        DEFAULT_MODEL, "--", "scattering model: directional (FHK14), standard (Jensen 2001) or better (d'Eon 2012)"
    )
    method: str = _setting(
        DEFAULT_METHOD,
        "--",
        "far-field method: exact (every pair), cutoff, tree, relight (operators prepared on first use that "
        "later lights on the same Scene reuse), or auto (tree, until the lights on the same Scene, material and "
        "tolerance have taken as long as preparing relight's operators would, then relight)",
    )
    device: str = _setting(
        DEFAULT_DEVICE,
        "--",
        "where exact, tree and relight (and so auto) sum their far field: cpu, gpu (an NVIDIA GPU, with pip install "
        '"translucency[gpu]"), or auto (a GPU where one works, for exact and relight, else '
        "the CPU); cutoff and the near field run on the CPU",
    )
    tol: float = _setting(
        DEFAULT_TOL,
        "1",
        "relative error allowed per vertex, at the 99th percentile (0.01: 1 %%): the far field's (cutoff, "
        "tree, relight, auto) and the proxy's of resolution auto; exact ignores it",
    )
    resolution: object = _setting(
        "auto",
        "mm",
        "where B is computed: auto (on a proxy only where its expected error, which grows with its edge over "
        "the diffusion length, is within the tolerance; at the default tolerance that is every vertex of any "
        "scan measured), full (every vertex), or a proxy edge length in mm",
    )
    shadows: bool = _setting(
        True,
        "--",
        "Embree shadow rays (off: every front-facing vertex is lit)",
        flag="no shadow rays: every front-facing vertex is lit",
    )
    per_direction: bool = _setting(
        False, "--", "solve each light sample with its own refracted direction (exact for several lights)"
    )
    exposure: object = _setting(None, "1", "display exposure (default: automatic)")
    memory_limit: object = _setting(
        None,
        "GB",
        "memory the process may use, GB (default: what the machine has available); a solve that would need "
        "more runs on a coarser proxy or stops with a message",
    )
    time_limit: object = _setting(
        DEFAULT_TIME_LIMIT_S,
        "s",
        "seconds a light's solve may take by its estimate, its bounces included (relight: its operators' "
        "preparation; None: no limit); over it the solve runs on a coarser proxy, sized to what is left after making "
        "it, or stops with a message",
        flag="seconds a light's solve may take by its estimate, its bounces included (relight: its operators' "
        "preparation); over it the solve runs on a coarser proxy, sized to what is left after making it, or stops "
        "with a message",
    )
    up: str = _setting("auto", "--", "the scan's up axis, x, y, z, -x, -y, -z, or auto (inferred from the shape)")
    bounces: int = _setting(
        DEFAULT_BOUNCES,
        "1",
        "times the light that leaves the surface (subsurface exitance and the boundary's mirror reflection of "
        f"the lights) and reaches it again is let in and solved again, 0 to {MAX_BOUNCES}; each costs a ray "
        "gather and a solve",
    )
    albedo: str = _setting(
        "material",
        "--",
        "material, or vertex_colors: the scan's colours (per vertex, or its texture sampled at the vertices) as "
        "the diffuse reflectance, with the material's mean free path, g and eta (docs/physics.md 6.5)",
        flag="the scan's colours (per vertex, or its texture sampled at the vertices) as the diffuse reflectance, "
        "with the material's mean free path, g and eta (docs/physics.md 6.5)",
    )

    def __post_init__(self):
        from ...io.upright import parse_up
        from ...scatter.budget import check_limits

        object.__setattr__(self, "material", resolve_medium(self.material))
        check_model(self.model)
        check_method(self.method)
        if check_device(self.device) == "gpu":  # a GPU that cannot be had, or a method it does not run: said now
            from ...scatter.gpu.probe import pair_device

            pair_device(self.device, self.method)
        check_tol(self.tol)
        object.__setattr__(self, "bounces", check_bounces(self.bounces))
        object.__setattr__(self, "resolution", parse_resolution(self.resolution))
        if not (self.exposure is None or _positive(self.exposure)):
            raise InvalidParameterError(f"{setting_name('exposure')} must be a positive number, got {self.exposure!r}.")
        check_limits(self.memory_limit, self.time_limit)
        object.__setattr__(self, "up", parse_up(self.up))
        object.__setattr__(self, "shadows", bool(self.shadows))
        object.__setattr__(self, "per_direction", bool(self.per_direction))
        if self.albedo not in ALBEDO_SOURCES:
            raise InvalidParameterError(
                f"{setting_name('albedo')} must be one of {', '.join(ALBEDO_SOURCES)}, got {self.albedo!r}."
            )

    def replace(self, **changes) -> ShadeSettings:
        """A copy with some fields changed (validated again); an unknown name is a sentence."""
        names = [field.name for field in dataclasses.fields(self)]
        unknown = sorted(set(changes) - set(names))
        if unknown:
            raise InvalidParameterError(
                f"unknown setting {', '.join(map(repr, unknown))}; the settings are {', '.join(names)}."
            )
        return dataclasses.replace(self, **changes)

    def metadata(self, lights, resolution: str) -> dict:
        """The settings as a result and a bake record them, with the ``lights`` and the ``resolution``
        used (a description); the exposure used, the unit and the up axis are the result's."""
        from ... import __version__
        from ...scatter.appearance import appearance_of

        reflectance, _ = appearance_of(self.material)
        return {
            "version": __version__,
            "material": self.material.name,
            # the definition in full: coefficients (a TOML or JSON material file of sigma_a, sigma_s, g, eta
            # gives it back) and the look they have (docs/physics.md 6.4)
            "coefficients": {**self.material.describe(), "diffuse_reflectance": reflectance.tolist()},
            "lights": [light.to_dict() for light in lights],
            "model": self.model,
            "method": self.method,
            "device": self.device,
            "tolerance": self.tol,
            "resolution": resolution,
            "shadows": self.shadows,
            "light_summation": "per direction" if self.per_direction else "aggregated per vertex",
            "bounces": self.bounces,
            "albedo": "the scan's colours as its diffuse reflectance" if self.albedo == "vertex_colors" else "material",
        }


def viewer_settings() -> ShadeSettings:
    """The viewer's default settings: the shading defaults with :data:`VIEWER_METHOD` and :data:`VIEWER_TOL`."""
    return ShadeSettings(method=VIEWER_METHOD, tol=VIEWER_TOL)


#: The fields of :class:`ShadeSettings` by name.
FIELDS = {field.name: field for field in dataclasses.fields(ShadeSettings)}
#: Help text of each field, as the command line's ``--help`` gives it (argparse's ``%%`` for a per cent sign).
HELP = {name: field.metadata["flag"] for name, field in FIELDS.items()}


def settings_with(settings: ShadeSettings | None = None, **changes) -> ShadeSettings:
    """The record an entry point solves with: ``settings`` (default: every field's default) with the fields
    given in ``changes`` (the entry point's keyword shortcuts, forwarded as given) replaced. An unknown name, or
    ``settings`` that is not a record, is a sentence."""
    if settings is None:
        settings = ShadeSettings()
    elif not isinstance(settings, ShadeSettings):
        raise InvalidParameterError(
            f"settings must be a ShadeSettings record (translucency.ShadeSettings(...)), got {type(settings).__name__}."
        )
    return settings.replace(**changes) if changes else settings


def settings_table() -> str:
    """The fields of :class:`ShadeSettings` as a reStructuredText table: name, default, unit and help."""
    rows = [
        (name, repr(field.default), field.metadata["unit"], field.metadata["help"].replace("%%", "%"))
        for name, field in FIELDS.items()
    ]
    widths = [max(len(row[k]) for row in rows + [("setting", "default", "unit", "meaning")]) for k in range(3)]
    rule = " ".join("=" * w for w in widths) + " " + "=" * 10
    lines = [rule, " ".join(h.ljust(w) for h, w in zip(("setting", "default", "unit"), widths)) + " meaning", rule]
    lines += [" ".join(cell.ljust(w) for cell, w in zip(row[:3], widths)) + " " + row[3] for row in rows]
    return "\n".join(lines + [rule])


def parameters_section() -> str:
    """The fields of :class:`ShadeSettings` as a numpydoc ``Parameters`` section: name, unit, default and help."""
    lines = ["Parameters", "----------"]
    for name, field in FIELDS.items():
        unit = field.metadata["unit"]
        lines.append(f"{name} : default {field.default!r}" + ("" if unit == "--" else f", {unit}"))
        lines.append("    " + field.metadata["help"].replace("%%", "%"))
    return "\n".join(lines)


__doc__ += "\n" + settings_table() + "\n"
ShadeSettings.__doc__ += "\n\n" + parameters_section() + "\n"


def resolve_medium(material):
    """A :class:`~translucency.scatter.medium.Medium` from a catalogue name, catalogue entry, medium,
    material file (``.toml`` or ``.json``) or definition mapping (:mod:`translucency.scatter.definition`)."""
    from collections.abc import Mapping

    from ...errors import UnknownMaterialError
    from ...io.material_file import is_material_file, read_material_table
    from ...scatter.definition import medium_from_definition
    from ...scatter.materials import Material, lookup_key
    from ...scatter.materials import material as lookup
    from ...scatter.medium import Medium

    if isinstance(material, Medium):
        return material
    if isinstance(material, Material):
        return material.medium()
    if isinstance(material, Mapping):
        return medium_from_definition(material)
    if is_material_file(material):
        return medium_from_definition(read_material_table(material), f"material file {material}")
    try:
        return lookup(material).medium()
    except UnknownMaterialError as exc:
        own = user_material_files().get(lookup_key(str(material)))
        if own is None:
            raise UnknownMaterialError(
                f"{exc} Your own materials go in {user_materials_folder()} as NAME.toml or NAME.json files."
            ) from None
        return medium_from_definition(read_material_table(own), f"material file {own}")


#: The environment variable naming the folder of the user's own materials (:func:`user_materials_folder`).
MATERIALS_FOLDER_ENV = "TRANSLUCENCY_MATERIALS"


def user_materials_folder() -> Path:
    """The folder of the user's own materials, one ``NAME.toml`` or ``NAME.json`` file each, found by name
    after the catalogue: ``$TRANSLUCENCY_MATERIALS``, else ``$XDG_CONFIG_HOME/translucency/materials``, else
    ``~/.config/translucency/materials``."""
    import os

    if os.environ.get(MATERIALS_FOLDER_ENV):
        return Path(os.environ[MATERIALS_FOLDER_ENV]).expanduser()
    config = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(config) / "translucency" / "materials"


def user_material_files() -> dict:
    """The user's material files by lookup key (:func:`~translucency.scatter.materials.lookup_key` of the
    file's stem), in name order; empty when the folder does not exist."""
    from ...io.material_file import MATERIAL_SUFFIXES
    from ...scatter.materials import lookup_key

    folder = user_materials_folder()
    if not folder.is_dir():
        return {}
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in MATERIAL_SUFFIXES and p.is_file())
    return {lookup_key(p.stem): p for p in files}
