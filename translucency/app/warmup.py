"""The solver's compiled kernels: say when they are being compiled, and compile them ahead of use.

numba compiles a kernel the first time it is called and keeps the machine code in its cache (next to
the sources, or in ``NUMBA_CACHE_DIR``); later runs load it. A first run therefore waits for the
compiler (bench/README.md, "First run", measures how long). Two helpers:

* :func:`compile_notice` calls a function once, when numba really starts compiling one of the
  solver's kernels (numba's ``numba:compile`` event, which fires on a cache miss only), so the
  command line can say why it is quiet;
* :func:`warm_up` (``python -m translucency.app.warmup``, run by ``scripts/setup.sh``) compiles
  the kernels the main job uses by shading a small synthetic surface, unless every one of them is
  already in the cache (:func:`cold_kernels`, read from numba's cache index). numba compiles on one core
  and holds the interpreter while it does, so relighting's own kernels are compiled in a second process
  (:func:`compile_relighting`) while this one compiles the cleaning's and ``tree``'s.
"""

from __future__ import annotations

import argparse
import contextlib
import glob
import inspect
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from ..geometry import measure, morton, topology
from ..scatter import cutoff, fresnel, hierarchy, irradiance, kernels, listsums, nearfield, relight, surface, treewalk

#: The compiled kernels the main job's solve calls (``tree`` method, near field), the viewer's relighting and the
#: cleaning of a scan, as each module lists them.
MAIN_JOB_KERNELS = (
    *kernels.DIRECTIONAL_ROW_KERNELS,
    *listsums.LIST_KERNELS,
    *hierarchy.TREE_KERNELS,
    *cutoff.LARGEST_KERNELS,
    *treewalk.WALK_KERNELS,
    *nearfield.NEAR_FIELD_KERNELS,
    *relight.RELIGHT_KERNELS,
    *irradiance.LIGHT_KERNELS,
    *fresnel.FRESNEL_KERNELS,
    *morton.MORTON_KERNELS,
    *surface.ORDER_KERNELS,
    *topology.CLEANING_KERNELS,
    *measure.CLEANING_KERNELS,
)

NOTICE = "compiling the solver's kernels (the first run, and the first after an update; a minute or two) ..."

#: The warm-up's light (the plane's normal is +z).
LIGHT_DIRECTION = (0.3, 0.2, 1.0)

#: The longest the warm-up waits for its second process once its own part is done (s); past it, it stops the
#: process and compiles what is left itself.
HELPER_SECONDS = 600.0

#: This module's import name, also where ``python -m`` runs it as ``__main__`` (the second process imports it).
MODULE = __spec__.name if __spec__ is not None else __name__


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
    return [kernel.py_func.__qualname__ for kernel in MAIN_JOB_KERNELS if not _is_cached(kernel)]


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


def compile_relighting() -> None:
    """Compile relighting's own kernels (its near and far operators and a light's product with them) by preparing
    the operators of :func:`_plane` in marble at the viewer's ``tol`` and applying them to one light, as a shade
    with ``method="relight"`` would, less its first light's check against ``tree``; and first the near field's sum
    over listed points (:func:`~translucency.scatter.kernels.indexed_sum`, with the argument types the near field
    gives it and empty lists), which the first process reaches after the cleaning's kernels and the near lists'
    (where it gets there first, it compiles the sum too: the same code, written to the cache twice). The body of the
    second process of :func:`warm_up`; the kernels land in numba's cache, where the first process then finds them."""
    from ..scatter import kernels, solve
    from ..scatter.irradiance import incident_flux
    from ..scatter.lights import DirectionalLight
    from ..scatter.materials import material
    from ..scatter.surface import SurfaceGeometry, spatial_order
    from .shading.settings import VIEWER_TOL

    points, triangles, normals = _plane()
    medium = material("marble").medium()
    n_c = medium.n_channels
    params = kernels.channel_parameters(medium.sigma_a, medium.sigma_s, medium.g, medium.eta)
    lanes = kernels.channel_lanes(params, np.arange(n_c), n_c)
    starts, counts, columns = (np.zeros(1, dtype=np.int64) for _ in range(3))  # one receiver, nothing listed
    table, weights = np.zeros((9, 1)), np.zeros((n_c, 1))
    model = kernels.MODELS["directional"]
    kernels.indexed_sum(model, points[:1], normals[:1], table, weights, starts, counts, columns, np.zeros(1), lanes)
    geometry = spatial_order(SurfaceGeometry(points, triangles, normals))[0]
    areas = geometry.vertex_areas
    light = incident_flux(geometry.points, geometry.normals, areas, DirectionalLight(LIGHT_DIRECTION, 1.0), medium.eta)
    operator, _ = solve.relight_operator(geometry, medium, "directional", VIEWER_TOL)
    operator.apply(areas, light.phi_rgb, light.w12, {})


def _second_process(errors) -> subprocess.Popen | None:
    """:func:`compile_relighting` in a process of its own, its output discarded and its errors written to the file
    ``errors`` (where it fails, the first process compiles what it left); None where no second core would run it."""
    from ..threads import thread_count

    if thread_count() < 2:
        return None
    command = [sys.executable, "-c", f"from {MODULE} import compile_relighting; compile_relighting()"]
    try:
        return subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=errors)
    except OSError:
        return None


def _stop(helper: subprocess.Popen | None, wait: float = 0.0) -> None:
    """Wait up to ``wait`` seconds for ``helper`` to end, then end it."""
    if helper is None:
        return
    try:
        helper.wait(timeout=wait)
    except subprocess.TimeoutExpired:
        pass
    if helper.poll() is None:
        helper.kill()
        helper.wait()


def _failure(helper: subprocess.Popen | None, errors) -> str | None:
    """One line on a second process that ended with an error (its last line of output), or None."""
    if helper is None or helper.returncode == 0:
        return None
    errors.seek(0)
    lines = [line.strip() for line in errors.read().decode(errors="replace").splitlines() if line.strip()]
    said = lines[-1] if lines else f"exit status {helper.returncode}"
    return f"the second compiling process stopped ({said}); its kernels are compiled here instead"


def warm_up(force: bool = False) -> float:
    """Compile the kernels the main job and the viewer use (the cleaning of a small plane, a ``tree`` shade of
    it in marble, and one with ``relight``, whose own kernels a second process compiles meanwhile:
    :func:`compile_relighting`); returns the seconds it took (0 when every kernel was already cached and ``force``
    is false)."""
    if not force and not cold_kernels():
        return 0.0
    from .shading.settings import VIEWER_METHOD, VIEWER_TOL, ShadeSettings

    start = time.perf_counter()
    with tempfile.TemporaryFile() as errors:
        helper = _second_process(errors)
        try:
            scene, light = _compile_main_job()
            _stop(helper, wait=HELPER_SECONDS)
        finally:
            _stop(helper)
        failure = _failure(helper, errors)
    if failure:
        print(failure, file=sys.stderr, flush=True)
    # relighting: its own kernels from the cache the second process filled (or compiled here where it failed)
    scene.shade_with(ShadeSettings(method=VIEWER_METHOD, tol=VIEWER_TOL, bounces=0, resolution="full", up="+z"), light)
    return time.perf_counter() - start


def _compile_main_job():
    """The first process's part of :func:`warm_up`: the cleaning's kernels and a ``tree`` shade of :func:`_plane`
    in marble; ``(scene, light)`` for the shade with ``relight`` that follows."""
    from ..geometry import proximity
    from ..geometry.mesh import TriangleMesh
    from ..scatter.lights import DirectionalLight
    from .shading.scene import Scene
    from .shading.settings import ShadeSettings

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
    scene = Scene(TriangleMesh(points, triangles), shadows=False, up="+z")
    light = DirectionalLight(LIGHT_DIRECTION, 1.0)
    scene.shade_with(ShadeSettings(method="tree", tol=1e-2, bounces=0, resolution="full", up="+z"), light)
    return scene, light


def main(argv: list[str] | None = None) -> int:
    """``python -m translucency.app.warmup [--force]``: compile the main job's kernels once."""
    parser = argparse.ArgumentParser(prog="python -m translucency.app.warmup", description=main.__doc__)
    parser.add_argument("--force", action="store_true", help="solve the warm-up surface even when the cache is warm")
    args = parser.parse_args(argv)
    with compile_notice(lambda: print(NOTICE, flush=True)):
        seconds = warm_up(force=args.force)
    if seconds:
        print(f"the solver's kernels are ready ({seconds:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
