"""What a viewer saves: the bake of the current result at the display exposure, and the names of its files."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..display import display_colors
from ..shading.result import write_result


def file_stem(name: str, material: str, model: str) -> str:
    """Stem of saved files: ``<name>_<material>_<model>`` (``name``'s own stem)."""
    return f"{Path(name).stem}_{material}_{model}"


def numbered_paths(folder, stem: str, suffixes=(".png", ".ply")) -> list[Path]:
    """``<folder>/<stem>_<n><suffix>`` for each suffix, with the first ``n`` (three digits) none of them is taken."""
    folder, index = Path(folder), 0
    while any((folder / f"{stem}_{index:03d}{suffix}").exists() for suffix in suffixes):
        index += 1
    return [folder / f"{stem}_{index:03d}{suffix}" for suffix in suffixes]


def write_bake(result, exposure: float, path) -> Path:
    """Write ``result`` as a baked PLY with colours at the display ``exposure`` (linear factor); returns the path.

    A bake holds the radiance toward the normal, ``T21(eta, 1) B`` (docs/physics.md §5.3): it does not depend on
    the view.
    """
    colors, _ = display_colors(result.radiance, exposure)
    return write_result(
        dataclasses.replace(
            result, colors=colors, exposure=exposure, metadata=dict(result.metadata, exposure=exposure)
        ),
        path,
    )
