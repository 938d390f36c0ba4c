"""The solver's compiled kernels: say when they are being compiled, and compile them ahead of use.

numba compiles a kernel the first time it is called and keeps the machine code in its cache (next to
the sources, or in ``NUMBA_CACHE_DIR``); later runs load it. A first run therefore waits for the
compiler (about 10 s on two cores for what the main job uses). Two helpers:

* :func:`compile_notice` calls a function once, when numba really starts compiling one of the
  solver's kernels (numba's ``numba:compile`` event, which fires on a cache miss only), so the
  command line can say why it is quiet;
* :func:`warm_up` (``python -m translucency.scatter.warmup``, run by ``scripts/setup.sh``) compiles
  the kernels the main job uses by solving a small synthetic surface, unless every one of them is
  already in the cache (:func:`cold_kernels`, read from numba's cache index).
"""

from __future__ import annotations

import argparse
import contextlib
import glob
import inspect
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

#: Kernels (module, name) the main job's solve calls (``tree`` method, near field), the viewer's relighting and
#: the cleaning of a scan.
MAIN_JOB_KERNELS = (
    ("translucency.scatter.kernels", "_indexed_rows_directional"),
    ("translucency.scatter.kernels", "_grouped_rows_directional"),
    ("translucency.scatter.hierarchy", "_traverse"),
    ("translucency.scatter.hierarchy", "_build"),
    ("translucency.scatter.hierarchy", "_boxes"),
    ("translucency.scatter.hierarchy", "_leaf_sums"),
    ("translucency.scatter.nearfield", "_near_pass"),
    ("translucency.scatter.nearfield", "_fill_shared_points"),
    ("translucency.scatter.nearfield", "_list_points"),
    ("translucency.scatter.nearfield", "_refined_points"),
    # the viewer's relighting (its default method)
    ("translucency.scatter.relight", "_fill_coefficients"),
    ("translucency.scatter.relight", "_apply_quantised"),
    ("translucency.scatter.relight", "_apply_rows"),
    ("translucency.scatter.nearfield", "_operator_rows"),
    # the cleaning of a scan (its defect count, orientation and normals)
    ("translucency.geometry.topology", "_unique_edges"),
    ("translucency.geometry.topology", "_manifold_pairs"),
    ("translucency.geometry.topology", "_face_components"),
    ("translucency.geometry.topology", "_non_manifold_vertices"),
    ("translucency.geometry.topology", "_duplicate_triangles"),
    ("translucency.geometry.topology", "_first_at_same_position"),
    ("translucency.geometry.measure", "_cross_products"),
    ("translucency.geometry.measure", "_row_lengths"),
    ("translucency.geometry.measure", "_unit_rows"),
    ("translucency.geometry.measure", "_vertex_sums"),
    ("translucency.geometry.measure", "_degenerate"),
    ("translucency.geometry.measure", "_edge_lengths"),
    ("translucency.geometry.measure", "_centroids"),
    # the up axis of a scan (its default light)
    ("translucency.geometry.measure", "_area_centroids"),
    ("translucency.geometry.measure", "_extremes"),
    ("translucency.geometry.measure", "_outside_or_on"),
)

NOTICE = "compiling the solver's kernels (first run only, about 30-90 s) ..."


@contextlib.contextmanager
def compile_notice(say: Callable[[], None]) -> Iterator[None]:
    """Within the block, call ``say()`` once when numba starts compiling one of the solver's kernels
    (a function of ``translucency``: the solver's, and the cleaning's of :data:`MAIN_JOB_KERNELS`).

    Only real compilation counts: numba raises ``numba:compile`` on a cache miss, not when it loads a
    kernel from its cache (wherever ``NUMBA_CACHE_DIR`` puts it).
    """
    from numba.core import event

    class Listener(event.Listener):
        said = False

        def on_start(self, ev):
            dispatcher = (ev.data or {}).get("dispatcher")
            module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
            if not self.said and module.startswith("translucency."):
                self.said = True
                say()

        def on_end(self, ev):
            pass

    listener = Listener()
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)


def _is_cached(dispatcher) -> bool:
    """Whether numba's on-disk cache holds a compiled version of ``dispatcher`` for its current source.

    Read from the files only (numba's public ``stats.cache_path`` and its file naming: an index
    ``<file>.<function>-<line>.py<XY>.nbi`` beside one ``.nbc`` per compiled signature); an index older
    than the source file is stale, as numba itself would find it.
    """
    function = dispatcher.py_func
    source = Path(inspect.getsourcefile(function))
    python = f"py{sys.version_info[0]}{sys.version_info[1]}"
    stem = f"{source.stem}.{function.__qualname__}-{function.__code__.co_firstlineno}.{python}"
    folder = Path(dispatcher.stats.cache_path)
    index = folder / f"{stem}.nbi"
    try:
        fresh = index.stat().st_mtime >= source.stat().st_mtime
    except OSError:
        return False
    return fresh and any(folder.glob(f"{glob.escape(stem)}.*.nbc"))


def cold_kernels() -> list[str]:
    """Names of the main job's kernels that numba's cache holds no compiled version of (all of them
    when the cache cannot be read)."""
    import importlib

    return [name for module, name in MAIN_JOB_KERNELS if not _is_cached(getattr(importlib.import_module(module), name))]


def _plane(n: int = 24, spacing: float = 1.0):
    """A flat square of ``n x n`` vertices (mm), two triangles per cell, normals +z."""
    u, v = np.meshgrid(np.arange(n, dtype=np.float64), np.arange(n, dtype=np.float64), indexing="ij")
    points = np.column_stack([u.ravel() * spacing, v.ravel() * spacing, np.zeros(n * n)])
    corner = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    triangles = np.concatenate(
        [np.column_stack([corner, corner + n, corner + 1]), np.column_stack([corner + 1, corner + n, corner + n + 1])]
    ).astype(np.int64)
    normals = np.tile([0.0, 0.0, 1.0], (n * n, 1))
    return points, triangles, normals


def warm_up(force: bool = False) -> float:
    """Compile the kernels the main job and the viewer use (the cleaning of a small plane, a ``tree`` solve of
    it in marble, and one with ``relight``); returns the seconds it took (0 when every kernel was already
    cached and ``force`` is false)."""
    if not force and not cold_kernels():
        return 0.0
    from ..geometry import measure, proximity, topology
    from .materials import material
    from .names import DEFAULT_METHOD, DEFAULT_TOL, VIEWER_METHOD, VIEWER_TOL
    from .solve import SurfaceGeometry, solve

    start = time.perf_counter()
    points, triangles, normals = _plane()
    # what the cleaning of a scan counts (translucency.io.defects) and computes
    edges, edge_of_corner = topology.unique_edges(triangles)
    faces_per_edge = np.bincount(edge_of_corner.ravel(), minlength=len(edges))
    topology.count_non_manifold_vertices(triangles, edge_of_corner, faces_per_edge, len(points))
    topology.face_components(triangles, edge_of_corner)
    topology.duplicate_triangles(triangles)
    topology.first_at_same_position(points)
    measure.degenerate_triangles(points, triangles, 1e-10)
    measure.vertex_normals(points, triangles)
    # the up axis (translucency.io.upright): the surface's centroid and the convex hull's candidates
    measure.area_centroids(points, triangles)
    measure.hull_candidates(np.random.default_rng(0).normal(size=(4 * measure.CULL_DIRECTIONS + 1, 3)))
    # and the mapping of a scan onto its proxy (the viewer's screenshot)
    proximity.closest_points_on_triangles(points + 0.1 * normals, points, triangles)
    medium = material("marble").medium()
    phi = np.ones((points.shape[0], medium.n_channels))
    phi[::5] = 0.0  # unlit vertices too, as under shadows
    w12 = np.tile([0.0, 0.0, -1.0], (points.shape[0], 1))
    surface = SurfaceGeometry(points, triangles, normals)
    solve(surface, phi, w12, medium, method=DEFAULT_METHOD, tol=DEFAULT_TOL)
    solve(surface, phi, w12, medium, method=VIEWER_METHOD, tol=VIEWER_TOL)
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    """``python -m translucency.scatter.warmup [--force]``: compile the main job's kernels once."""
    parser = argparse.ArgumentParser(prog="python -m translucency.scatter.warmup", description=main.__doc__)
    parser.add_argument("--force", action="store_true", help="solve the warm-up surface even when the cache is warm")
    args = parser.parse_args(argv)
    with compile_notice(lambda: print(NOTICE, flush=True)):
        seconds = warm_up(force=args.force)
    if seconds:
        print(f"the solver's kernels are ready ({seconds:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
