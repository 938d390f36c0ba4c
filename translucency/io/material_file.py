"""Material files: a TOML or JSON table of one material definition (its keys:
:mod:`translucency.scatter.definition`).

Read here (the file and its syntax, each error one sentence naming the file); the keys are checked and
turned into a medium by the definition, which the application layer calls with what is read here.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import InvalidParameterError
from .readable import regular_file

__all__ = ["MATERIAL_SUFFIXES", "is_material_file", "read_material_table"]

#: File name endings read as material files.
MATERIAL_SUFFIXES = (".toml", ".json")


def is_material_file(name) -> bool:
    """Whether ``name`` (a ``--material`` value) names a material file by its ending, not a catalogue entry."""
    return isinstance(name, (str, Path)) and Path(str(name)).suffix.lower() in MATERIAL_SUFFIXES


def _toml():
    """The TOML reader: the standard library's (Python 3.11+) or tomli."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        try:
            import tomli as tomllib
        except ModuleNotFoundError:
            raise InvalidParameterError(
                "TOML material files need Python 3.11 or the tomli package; write the material as JSON instead."
            ) from None
    return tomllib


def read_material_table(path) -> dict:
    """The table of a TOML or JSON material file, with ``name`` set to the file's stem when it has none."""
    path = regular_file(path, InvalidParameterError, "material file", "TOML or JSON file")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InvalidParameterError(
            f"material file {path} is not UTF-8 text; save it as a TOML or JSON text file."
        ) from None
    except OSError as exc:
        raise InvalidParameterError(
            f"material file {path} cannot be read ({exc.strerror or 'refused'}); check the file and the disk."
        ) from None
    if path.suffix.lower() == ".toml":
        toml = _toml()
        try:
            table = toml.loads(text)
        except toml.TOMLDecodeError as exc:
            raise InvalidParameterError(f"material file {path} is not valid TOML: {exc}.") from None
    else:
        try:
            table = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InvalidParameterError(f"material file {path} is not valid JSON: {exc}.") from None
    if not isinstance(table, dict):
        raise InvalidParameterError(f"material file {path} must hold one table of keys and values.")
    table.setdefault("name", path.stem)
    return table
