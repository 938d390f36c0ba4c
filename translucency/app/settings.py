"""The shading settings: every choice a solve takes, its default, its check and its help text, once.

:class:`ShadeSettings` is what the command line (:mod:`translucency.app.options`), the viewer, batch
baking (:class:`~translucency.app.bake.BakeSettings` adds the files' unit and the lights) and
``compare`` build; it is validated on construction, with one sentence that names the setting as the
user wrote it (``--tol`` on the command line, ``tol`` in Python). :data:`HELP` holds the help text of
each field, from which the parser's ``--help`` is written; the bake's metadata records the same fields.
The model and method names, their defaults and their checks are :mod:`translucency.scatter.names`'.

========================= ============================================================== ==========
field                     meaning                                                        unit
========================= ============================================================== ==========
material                  catalogue name, entry or medium, stored as a ``Medium``         1/mm
model                     scattering model (:data:`~translucency.scatter.names.MODELS`)   --
method                    far-field method (:data:`~translucency.scatter.names.METHODS`)  --
tol                       relative error allowed per vertex (``cutoff``, ``tree``, auto)  1
resolution                ``"auto"``, ``"full"`` or a proxy edge length                    mm
shadows                   Embree shadow rays                                              --
per_direction             one solve per light sample (else aggregated per vertex)         --
exposure                  display exposure (None: automatic)                              1
memory_limit              memory the process may hold (None: what is available)           GB
time_limit                seconds a solve may take by its estimate (None: no limit)       s
up                        the scan's up axis, ``"x"`` ... ``"-z"`` or ``"auto"``           --
bounces                   times light leaving the surface enters again (0: never)         1
albedo                    ``"material"`` or ``"vertex_colors"`` (the scan's colour)         --
========================= ============================================================== ==========
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from pathlib import Path

from ..errors import InvalidParameterError, setting_name
from ..scatter.budget import DEFAULT_TIME_LIMIT_S
from ..scatter.names import (
    DEFAULT_BOUNCES,
    DEFAULT_METHOD,
    DEFAULT_MODEL,
    DEFAULT_TOL,
    MAX_BOUNCES,
    check_bounces,
    check_method,
    check_model,
    check_tol,
)

__all__ = [
    "ShadeSettings",
    "HELP",
    "DEFAULT_MATERIAL",
    "RESOLUTIONS",
    "ALBEDO_SOURCES",
    "parse_resolution",
    "resolve_medium",
]

DEFAULT_MATERIAL = "marble"
#: The named resolutions (besides a proxy edge length in mm).
RESOLUTIONS = ("full", "auto")
#: Where the albedo comes from: the material's own, or the scan's colour per vertex read as its diffuse
#: reflectance with the material's mean free path (docs/physics.md §6.5).
ALBEDO_SOURCES = ("material", "vertex_colors")

#: Help text of each field (the command line's ``--help``, for ``shadows`` its ``--no-shadows`` flag; the
#: defaults are added where the option is made).
HELP = {
    "material": "catalogue name (see 'translucency materials') or a material file, .toml or .json",
    "model": "scattering model",
    "method": "far-field method",
    "tol": "relative error allowed per vertex, at the 99th percentile (0.01: 1 %%): the far field's (cutoff, "
    "tree) and the proxy's of resolution auto",
    "resolution": "where B is computed: auto (on a proxy only where its expected error, measured to grow with its "
    "edge over the diffusion length, is within --tol; at the default tolerance every vertex of any scan measured), "
    "full (every vertex), or a proxy edge length in mm",
    "shadows": "no shadow rays: every front-facing vertex is lit",
    "per_direction": "solve each light sample with its own refracted direction (exact for several lights)",
    "exposure": "display exposure (default: automatic)",
    "memory_limit": "memory the process may use, GB (default: what the machine has available); a solve "
    "that would need more runs on a coarser proxy or stops with a message",
    "bounces": "times the light that leaves the surface (subsurface exitance and the boundary's mirror "
    f"reflection of the lights) and reaches it again is let in and solved again, 0 to {MAX_BOUNCES}; each "
    "costs a ray gather and a solve",
    "albedo": "the scan's colours (per vertex, or its texture sampled at the vertices) as the diffuse "
    "reflectance, with the material's mean free path, g and eta (docs/physics.md 6.5)",
    "time_limit": f"seconds a solve may take by its estimate (default {DEFAULT_TIME_LIMIT_S:g}); over it the solve "
    "runs on a coarser proxy or stops with a message",
}


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
    """Every setting of a solve, validated on construction (module docstring for the fields and units).

    Parameters
    ----------
    material : str or Material or Medium
        Catalogue name, entry or medium (coefficients in 1/mm); stored as a ``Medium``.
    model : {"directional", "standard", "better"}
        The BSSRDF (FHK14, Jensen 2001, d'Eon 2012).
    method : {"exact", "cutoff", "tree", "relight"}
        How the far field is summed (:func:`translucency.scatter.solve.solve`); ``relight`` prepares operators
        on first use that later lights on the same :class:`~translucency.app.pipeline.Scene` reuse.
    tol : float
        Relative error per vertex allowed to ``cutoff``, ``tree`` and ``relight``, and to the proxy of
        ``resolution="auto"``, in (0, 1).
    resolution : "auto", "full" or float
        Where ``B`` is computed (:func:`translucency.app.pipeline.shade`): ``"auto"`` (default) on a proxy only
        where its expected error is within ``tol``, ``"full"`` on every vertex, a number is a proxy edge in mm.
    shadows : bool
        Cast Embree shadow rays (off: every front-facing vertex is lit).
    per_direction : bool
        Solve once per light sample with its own refracted direction and add the results.
    exposure : float, optional
        Display exposure (automatic by default).
    memory_limit : float, optional
        GB the process may hold.
    time_limit : float or None
        Seconds a solve may take by its estimate (None: no limit).
    up : str
        The scan's up axis, ``"x"`` ... ``"-z"``, or ``"auto"`` (inferred); stored as ``"+x"`` ... or ``"auto"``.
    bounces : int
        Times the light leaving the surface that reaches it again is let in and solved again
        (docs/physics.md §7.4), 0 to :data:`~translucency.scatter.names.MAX_BOUNCES`.
    albedo : {"material", "vertex_colors"}
        The material's albedo, or the scan's colour per vertex read as its diffuse reflectance
        (:data:`ALBEDO_SOURCES`).
    """

    material: object = DEFAULT_MATERIAL
    model: str = DEFAULT_MODEL
    method: str = DEFAULT_METHOD
    tol: float = DEFAULT_TOL
    resolution: str | float = "auto"
    shadows: bool = True
    per_direction: bool = False
    exposure: float | None = None
    memory_limit: float | None = None
    time_limit: float | None = DEFAULT_TIME_LIMIT_S
    up: str = "auto"
    bounces: int = DEFAULT_BOUNCES
    albedo: str = "material"

    def __post_init__(self):
        from ..io.upright import parse_up
        from ..scatter.budget import check_limits

        object.__setattr__(self, "material", resolve_medium(self.material))
        check_model(self.model)
        check_method(self.method)
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
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def solver_keywords(self) -> dict:
        """Keyword arguments of :meth:`translucency.app.pipeline.Scene.shade` (all but ``shadows`` and
        ``up``, which are the :class:`~translucency.app.pipeline.Scene`'s)."""
        return {
            name: getattr(self, name)
            for name in (
                "material",
                "model",
                "method",
                "tol",
                "resolution",
                "exposure",
                "per_direction",
                "bounces",
                "albedo",
                "memory_limit",
                "time_limit",
            )
        }

    def metadata(self, lights, resolution: str) -> dict:
        """The settings as a result and a bake record them, with the ``lights`` and the ``resolution``
        used (a description); the exposure used, the unit and the up axis are the result's."""
        from .. import __version__
        from ..scatter.appearance import appearance_of

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
            "tolerance": self.tol,
            "resolution": resolution,
            "shadows": self.shadows,
            "light_summation": "per direction" if self.per_direction else "aggregated per vertex",
            "bounces": self.bounces,
            "albedo": "the scan's colours as its diffuse reflectance" if self.albedo == "vertex_colors" else "material",
        }


def resolve_medium(material):
    """A :class:`~translucency.scatter.medium.Medium` from a catalogue name, catalogue entry, medium,
    material file (``.toml`` or ``.json``) or definition mapping (:mod:`translucency.scatter.definition`)."""
    from collections.abc import Mapping

    from ..errors import UnknownMaterialError
    from ..io.material_file import is_material_file, read_material_table
    from ..scatter.definition import medium_from_definition
    from ..scatter.materials import Material, lookup_key
    from ..scatter.materials import material as lookup
    from ..scatter.medium import Medium

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
    from ..io.material_file import MATERIAL_SUFFIXES
    from ..scatter.materials import lookup_key

    folder = user_materials_folder()
    if not folder.is_dir():
        return {}
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in MATERIAL_SUFFIXES and p.is_file())
    return {lookup_key(p.stem): p for p in files}
