"""Fixtures of the io tests: generated meshes and the shared real scans (skipped when absent)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
MESHES = REPO / ".." / "shared" / "meshes"


def shared_scan(name: str) -> Path:
    """Path of a shared scan; skips the test when the folder or the file is absent."""
    path = MESHES / name
    if not path.is_file():
        pytest.skip(f"shared scan {name} not found (expected in ../shared/meshes)")
    return path


def load_scan(name: str, unit: str = "mm"):
    """Load a shared scan without the implausible-size warning (the files state no unit)."""
    from translucency.io import load_mesh

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_mesh(shared_scan(name), unit)


def icosphere(subdivisions: int = 2, radius: float = 10.0):
    """A closed, outward-oriented sphere: (points in mm, triangles)."""
    t = (1 + 5**0.5) / 2
    points = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=float
    )  # fmt: skip
    triangles = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
         [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
         [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    )  # fmt: skip
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middle = points[unique].mean(axis=1)
        middle /= np.linalg.norm(middle, axis=1, keepdims=True)
        m = len(points) + inverse.reshape(-1, 3)
        a, b, c = triangles.T
        ab, bc, ca = m.T
        triangles = np.concatenate([np.stack(x, axis=1) for x in ([a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca])])
        points = np.concatenate([points, middle])
    return points * radius, triangles.astype(np.int64)


def grid(n: int = 10, size: float = 10.0):
    """An open square of 2 n² triangles in the z = 0 plane, normals +z: (points, triangles)."""
    x, y = np.meshgrid(np.linspace(0, size, n + 1), np.linspace(0, size, n + 1), indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return points, triangles.astype(np.int64)


@pytest.fixture
def sphere():
    return icosphere(2, 10.0)


@pytest.fixture
def sphere_mesh():
    from translucency.io import TriangleMesh

    points, triangles = icosphere(3, 25.0)
    colors = np.clip(np.round((points / 25.0 + 1) * 127.5), 0, 255).astype(np.uint8)
    return TriangleMesh(points, triangles, {"colors": colors, "confidence": np.linspace(0, 1, len(points))})
