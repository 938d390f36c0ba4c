"""One scan solved on a Dask cluster: its receivers in blocks, the surface shared by the workers.

A :class:`BlockSolver` stands in for :func:`translucency.scatter.solve.solve` (the same arguments, the same
:class:`~translucency.scatter.solve.Solution`): the surface's arrays and the incident light are sent to every
worker once (``client.scatter(..., broadcast=True)``), each worker builds the surface, its spatial order, its
source tree and near lists once per scan and keeps them between blocks, and every block of receivers is one
task. The blocks are runs of the surface's spatial order whose lengths are multiples of the tree's groups of
receivers, so each receiver is solved with the same lists as in one local solve; the result is assembled in
the caller's order. Each task checks its own block against the worker's memory and time budget, so a scan
too large for one machine is solved by several.

Used by ``translucency bake --scheduler ADDRESS`` when it is given one scan (several scans go one per task:
:mod:`translucency.app.bake`). The relighting method keeps its operators in one process and is solved here.
"""

from __future__ import annotations

import time
import uuid

import numpy as np

from ...scatter.transport import GROUP_RECEIVERS, Solution, SurfaceGeometry, solve, spatial_order

__all__ = ["BlockSolver", "BLOCK_RECEIVERS"]

#: Receivers per task (rounded down to a multiple of the tree's groups of receivers).
BLOCK_RECEIVERS = 20_000
#: Statistics of the blocks' solves that add up (the others are the first block's).
_ADDED = ("pairs_evaluated", "pairs_skipped", "pairs_direct", "cluster_evaluations", "near_points", "lit_vertices")

#: On each worker: the surface of the scan it solves blocks of, by key (one scan at a time).
_SURFACES: dict = {}


def _surface(key: str, points, triangles, normals) -> SurfaceGeometry:
    """The worker's surface for ``key``, built on its first block and kept for the next ones."""
    held = _SURFACES.get(key)
    if held is None:
        _SURFACES.clear()
        held = _SURFACES[key] = SurfaceGeometry(points, triangles, normals)
    return held


def solve_block(key: str, arrays, phi, w12, medium, settings: dict, receivers) -> Solution:
    """One task: :func:`~translucency.scatter.solve.solve` on the worker's surface for ``receivers``."""
    return solve(_surface(key, *arrays), phi, w12, medium, receivers=receivers, **settings)


class BlockSolver:
    """:func:`~translucency.scatter.solve.solve` with the receivers solved in blocks on a Dask cluster.

    Parameters
    ----------
    client : distributed.Client
        The cluster's client; its workers need translucency installed (nothing is read from files).
    block_receivers : int
        Receivers per task (:data:`BLOCK_RECEIVERS`).
    """

    def __init__(self, client, block_receivers: int = BLOCK_RECEIVERS):
        self.client = client
        self.block_receivers = max(GROUP_RECEIVERS, int(block_receivers) // GROUP_RECEIVERS * GROUP_RECEIVERS)
        self._shared = None  # (geometry, key, futures of its arrays): sent once per surface

    def _surface_on_workers(self, geometry: SurfaceGeometry):
        if self._shared is None or self._shared[0] is not geometry:
            arrays = self.client.scatter(
                [geometry.points, geometry.triangles, geometry.normals], broadcast=True, hash=False
            )
            self._shared = (geometry, uuid.uuid4().hex, arrays)
        return self._shared[1], self._shared[2]

    def __call__(self, geometry, phi, w12, medium, *, receivers=None, progress=None, **settings) -> Solution:
        """``solve(geometry, phi, w12, medium, receivers=..., progress=..., **settings)``, in blocks on the
        cluster (the method ``relight`` here, in this process)."""
        if settings.get("method") == "relight" or (receivers is not None and len(receivers) == 0):
            return solve(geometry, phi, w12, medium, receivers=receivers, progress=progress, **settings)
        start = time.perf_counter()
        report = progress or (lambda stage, fraction: None)
        wanted = np.arange(geometry.n_vertices) if receivers is None else np.asarray(receivers, dtype=np.int64)
        _, _, rank = spatial_order(geometry)
        positions = np.argsort(rank[wanted], kind="stable")  # the receivers along the surface's spatial order
        blocks = [positions[k : k + self.block_receivers] for k in range(0, positions.size, self.block_receivers)]
        key, arrays = self._surface_on_workers(geometry)
        phi_f, w12_f = self.client.scatter([np.asarray(phi), np.asarray(w12)], broadcast=True, hash=False)
        futures = {
            self.client.submit(solve_block, key, arrays, phi_f, w12_f, medium, settings, wanted[block], pure=False): k
            for k, block in enumerate(blocks)
        }
        from distributed import as_completed

        B = np.zeros((wanted.size, medium.n_channels))
        stats, timings, solved = {}, {}, None
        report("blocks on the cluster", 0.0)
        for done, future in enumerate(as_completed(futures), start=1):
            part = future.result()
            B[blocks[futures[future]]] = part.B
            solved = solved or part
            for name in _ADDED:
                if name in part.stats:
                    stats[name] = stats.get(name, 0) + part.stats[name]
            for name, seconds in part.timings.items():
                timings[name] = timings.get(name, 0.0) + seconds
            report("blocks on the cluster", done / len(blocks))
        stats = {**solved.stats, **stats, "blocks": len(blocks), "cluster_seconds": time.perf_counter() - start}
        return Solution(B=B, receivers=wanted, stats=stats, timings=timings, settings=solved.settings)
