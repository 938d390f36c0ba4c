"""Memory and time a solve needs, estimated from cheap counts before any large allocation.

:func:`translucency.scatter.solve.solve` counts, on a sample of receivers, what the work depends on
(near triangles, near-field quadrature points, far-field evaluations per receiver), hands the counts
to :func:`estimate`, and gets back a plan: whether the near-triangle lists of every receiver can be
kept at once (as without a budget) or the receivers are processed in blocks whose lists are made
and dropped one after the other (the same result, to the bit, with the memory of one block), how
large the blocks are, the peak memory and the seconds the solve should take. A plan that does not
fit the memory budget even with the smallest blocks, or whose time is over the time budget, is
refused (:class:`~translucency.errors.BudgetError`, raised by the solver) before the work starts. The
sample itself makes nothing of the surface's size but the source tree: the far field's counts are the
tree's walk alone, the near field's are taken on the triangles around the sampled receivers.

The byte counts per vertex, triangle, near triangle and quadrature point follow the arrays the
solver allocates (listed at each constant); the rates are calibrations (``bench/budget.py``, where the
estimates are compared with the measured peak memory and time; summary in ``bench/README.md``, "Memory and
time budget").

=================== ================================================================ ======
symbol              meaning                                                          unit
=================== ================================================================ ======
n, m                vertices, triangles of the solver's mesh                         1
n_near              near triangles of a receiver (a vertex within the near radius)   1
points              near-field quadrature points evaluated at a receiver             1
own                 of those, the receiver's own points (fan rule, refined pieces)   1
far                 far-field evaluations (sources and clusters) of a receiver       1
budget              memory the solve may take on top of what the process holds       bytes
=================== ================================================================ ======

Everything here is arithmetic on numbers; what the operating system says about memory comes from
:mod:`translucency.memory`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InvalidParameterError, option

#: One gigabyte as ``memory_limit`` counts it (2**30 bytes, GiB).
GB = 2**30
#: Head-room left of the available memory: this fraction of it, and at least this many bytes.
HEADROOM_FRACTION = 0.10
HEADROOM_BYTES = 256 * 2**20
#: Bytes per vertex the solve holds throughout: positions and normals (given and Morton-ordered),
#: flux density and refracted direction (given, ordered, flux), areas, the source tree and its
#: aggregated table, ``B`` and its correction (the near field's point table holds a block's vertices only, and
#: counts with the block).
BYTES_PER_VERTEX = 704
#: Bytes per triangle: indices (given, ordered), triangle tables (diameters, centroids, edges) and the
#: vertex-to-triangle lists of the near-triangle grid (the edges and those lists int32).
BYTES_PER_TRIANGLE = 264
#: Bytes per triangle of a near-field block's point table: Dunavant points and edge midpoints (7 + 1.5
#: columns of 12 float64). A block of ``b`` receivers lists about ``(sqrt(2 b) + sqrt(k))**2 <= 4 b + 2 k``
#: triangles (a patch of ``2 b`` triangles and its rim, ``k`` near triangles per receiver).
BYTES_PER_TABLE_TRIANGLE = 8.5 * 12 * 8


def block_table_bytes(near_triangles: float) -> tuple[float, float]:
    """A near-field block's point table as ``(bytes per receiver of the block, bytes of its rim)`` for
    ``near_triangles`` near triangles per receiver: ``4 b + 2 k`` triangles of :data:`BYTES_PER_TABLE_TRIANGLE`
    (the bound above), the plan's and the blocks' one model."""
    return 4 * BYTES_PER_TABLE_TRIANGLE, 2 * BYTES_PER_TABLE_TRIANGLE * near_triangles


#: Bytes per triangle and numba thread: the stamps of the near lists (1 int32) and of the listing
#: of quadrature points (2 int32 per vertex and per edge of a block's table, counted here for the whole mesh).
BYTES_PER_TRIANGLE_THREAD = 4 + 2 * 4 * 1.5 + 2 * 4 * 0.5
#: Bytes of a near-triangle list entry (int32), kept for every receiver or for one block.
BYTES_PER_NEAR_TRIANGLE = 4
#: Every receiver's near lists are kept (for a later solve of the same surface: the viewer's) only up to this
#: size; above, each block of receivers lists its own and frees them (listing is a few % of a solve), so that
#: the memory of a large scan does not grow with them (they take the vertices times the near triangles per
#: receiver times :data:`BYTES_PER_NEAR_TRIANGLE`).
KEPT_LISTS_BYTES = 256 * 2**20
#: Bytes per near triangle while a receiver's points are listed: room for 10 columns (3 vertices and
#: 7 rule points) of an int64 index and a float64 factor.
BYTES_PER_NEAR_ROOM = 10 * 16
#: Bytes per own quadrature point: 9 + 3 float64, with a quarter more room.
BYTES_PER_OWN_POINT = 1.25 * 12 * 8
#: Far field of ``tree``: the sources and clusters of a block of 4096 receivers (1024 groups), an int64
#: column and a float64 factor each.
BYTES_PER_FAR_EVALUATION = 16 * 1024
#: Receivers a near-field call handles at least (below this the per-call overhead dominates).
MIN_BLOCK_RECEIVERS = 16
#: Near-field calls per solve when everything fits (the progress callback is called after each).
PROGRESS_STEPS = 16
#: Most receivers in a near-field call: its lists and its point table grow with it (about 1.5 kB a receiver on a
#: fine scan), and a call of more saves no time.
MAX_BLOCK_RECEIVERS = 128 * 2048
#: Safety factor on the sampled per-receiver counts (blocks are sized on the sample's mean).
SAMPLE_SAFETY = 1.5

#: Rates per numba thread: far-field evaluations per second by method, near-field quadrature points per
#: second, near-list entries per second (counting and filling), and the seconds per vertex of the set-up
#: (ordering, tables, tree). Calibrations on timed solves (``bench/budget.py``; bench/README.md, "Memory and time
#: budget"): ``tree``'s and the near field's on scans of 0.5-10M vertices on a quiet machine, at three quarters of
#: the rates measured there, since a time limit matters for scans of that size; other work on the cores slows a
#: solve below them.
FAR_RATE = {"exact": 40e6, "cutoff": 15e6, "tree": 32e6}
#: Pairs per second of ``exact`` on a GPU, the whole device: an estimate from published all-pairs kernels and the
#: pair's cost in simple interactions, not a calibration (bench/README.md, "GPU"). ``tree``'s walk is taken to be as
#: much slower per evaluation there as on the CPU when both summed in float64 (:data:`GPU_TREE_SHARE`).
GPU_PAIR_RATE = 2e10
#: ``tree``'s evaluations a second against ``exact``'s pairs on a GPU: the CPU's ratio (25 and 40 million a second
#: and thread) before its clusters were summed in float32; the GPU sums them in float64.
GPU_TREE_SHARE = 25e6 / 40e6
#: Near-field quadrature points per second on a GPU (a solve whose device is ``gpu``): each a pair and an interpolation,
#: made by a thread that branches as ``tree``'s walk does, so taken at that walk's rate. An estimate, as above.
GPU_NEAR_RATE = GPU_PAIR_RATE * GPU_TREE_SHARE
NEAR_RATE = 7e6
LIST_RATE = 60e6
SETUP_SECONDS_PER_VERTEX = 2e-6


@dataclass(frozen=True)
class SolveCounts:
    """What the work of one solve depends on (sampled per receiver where it varies).

    Attributes
    ----------
    n_vertices, n_triangles, n_receivers, n_lit, n_channels : int
        Sizes of the solve (``n_lit``: vertices with flux).
    threads : int
        numba threads.
    method : str
        Far-field method (``exact``, ``cutoff``, ``tree``).
    device : str
        Where the far field's pairs are summed: ``cpu`` or ``gpu``.
    near_triangles, near_points, own_points, far_evaluations : float
        Per receiver, the sample's means: near triangles, near-field quadrature points evaluated,
        of those the receiver's own, and far-field evaluations.
    """

    n_vertices: int
    n_triangles: int
    n_receivers: int
    n_lit: int
    n_channels: int
    threads: int
    method: str
    near_triangles: float
    near_points: float
    own_points: float
    far_evaluations: float
    device: str = "cpu"


@dataclass(frozen=True)
class SolveEstimate:
    """The plan of a solve and what it costs (:func:`estimate`).

    Attributes
    ----------
    base_bytes : float
        Per-vertex and per-triangle arrays held during the whole solve, bytes.
    far_bytes : float
        Extra memory of the far field, bytes.
    lists_bytes : float
        Near-triangle lists of every receiver at once, bytes.
    receiver_bytes : float
        Near-field memory per receiver of a block, bytes.
    keep_lists : bool
        The lists of every receiver are made at once and kept (as without a budget); otherwise
        receivers go in blocks of ``block_receivers``, each with its own lists.
    block_receivers : int
        Receivers per near-field call (blocks: of the sample's mean size).
    block_bytes : float
        Memory a block of receivers may take in the near field, bytes.
    own_points : float
        Own quadrature points per receiver (the sample's mean).
    peak_bytes : float
        Estimated peak memory of the solve on top of what the process held before it, bytes.
    seconds : float
        Estimated wall time, s.
    budget_bytes, time_limit : float or None
        The budgets it was planned for (None: none).
    fits : bool
        Within both budgets.
    bounces : int
        The bounces that ``seconds`` and ``time_limit`` hold besides the solve: 0 for one solve's plan; a light's
        whole estimate (:func:`translucency.scatter.transport.light_solves`) otherwise.
    least : bool
        ``seconds`` and ``peak_bytes`` are the least a solve of this size takes (:func:`size_floor`), not its plan.
    """

    base_bytes: float
    far_bytes: float
    lists_bytes: float
    receiver_bytes: float
    keep_lists: bool
    block_receivers: int
    block_bytes: float
    own_points: float
    peak_bytes: float
    seconds: float
    budget_bytes: float | None
    time_limit: float | None
    fits: bool
    bounces: int = 0
    least: bool = False

    def as_dict(self) -> dict:
        """The estimate as plain numbers (for a result's statistics)."""
        return asdict(self)

    @property
    def over_memory(self) -> bool:
        """The memory needed exceeds the memory budget."""
        return self.budget_bytes is not None and self.peak_bytes > self.budget_bytes

    @property
    def over_time(self) -> bool:
        """The estimated time exceeds the time budget."""
        return self.time_limit is not None and self.seconds > self.time_limit


def solve_seconds(counts: SolveCounts) -> float:
    """Estimated wall time (s) of a solve from its counts and the calibrated rates (:data:`FAR_RATE`, ...)."""
    threads = max(1, counts.threads)
    n_r = counts.n_receivers
    far_rate = FAR_RATE.get(counts.method, FAR_RATE["exact"])
    if counts.device == "gpu":
        share = GPU_TREE_SHARE if counts.method == "tree" else far_rate / FAR_RATE["exact"]
        far_rate = GPU_PAIR_RATE * share
    else:
        far_rate *= threads
    far = n_r * counts.far_evaluations / far_rate
    lists = 2 * n_r * counts.near_triangles / LIST_RATE
    setup = SETUP_SECONDS_PER_VERTEX * counts.n_vertices
    if counts.device == "gpu":  # the near field's quadrature on the GPU, its lists on the CPU
        return far + lists / threads + n_r * counts.near_points / GPU_NEAR_RATE + setup
    return far + (lists + n_r * counts.near_points / NEAR_RATE) / threads + setup


def estimate(
    counts: SolveCounts,
    budget_bytes: float | None = None,
    time_limit: float | None = None,
    keep_lists: bool | None = None,
) -> SolveEstimate:
    """Plan a solve: keep every near list or go in blocks, the block size, peak memory (bytes), time (s).

    Parameters
    ----------
    counts : SolveCounts
    budget_bytes : float, optional
        Memory the solve may take, bytes (None: no limit).
    time_limit : float, optional
        Seconds the solve may take (None: no limit).
    keep_lists : bool, optional
        Force keeping every receiver's lists (True) or blocks (False); by default the lists are kept
        when they take at most :data:`KEPT_LISTS_BYTES` and that fits the budget.

    Returns
    -------
    SolveEstimate
    """
    n, m, n_r = counts.n_vertices, counts.n_triangles, counts.n_receivers
    base = (
        BYTES_PER_VERTEX * n
        + BYTES_PER_TRIANGLE * m
        + BYTES_PER_TRIANGLE_THREAD * m * max(1, counts.threads)
        + 3 * 8 * counts.n_channels * n_r
    )
    far = BYTES_PER_FAR_EVALUATION * counts.far_evaluations if counts.method == "tree" else 9 * 8 * counts.n_lit
    near_triangles = SAMPLE_SAFETY * counts.near_triangles
    lists = BYTES_PER_NEAR_TRIANGLE * n_r * near_triangles
    table_per_receiver, rim = block_table_bytes(near_triangles)
    per_receiver = (
        BYTES_PER_NEAR_ROOM * near_triangles
        + BYTES_PER_OWN_POINT * SAMPLE_SAFETY * counts.own_points
        + table_per_receiver
    )
    steps = max(1, math.ceil(n_r / PROGRESS_STEPS))
    usual = min(
        n_r, MAX_BLOCK_RECEIVERS, max(2048, -(-steps // 2048) * 2048)
    )  # a multiple of the near field's own blocks
    keep_peak = base + max(far, lists + rim + per_receiver * usual)
    if keep_lists is None:  # kept for a later solve of the same receivers when they are small and fit
        keep_lists = lists <= KEPT_LISTS_BYTES and (budget_bytes is None or keep_peak <= budget_bytes)
    if keep_lists:
        block, block_bytes, peak = usual, rim + per_receiver * usual, keep_peak
    else:
        per_block = per_receiver + BYTES_PER_NEAR_TRIANGLE * near_triangles
        room = (budget_bytes - base - rim) if budget_bytes is not None else per_block * usual
        block = int(min(usual, max(MIN_BLOCK_RECEIVERS, room // per_block if per_block > 0 else usual)))
        block_bytes = rim + per_block * block
        peak = base + max(far, block_bytes)
    seconds = solve_seconds(counts)
    fits = (budget_bytes is None or peak <= budget_bytes) and (time_limit is None or seconds <= time_limit)
    return SolveEstimate(
        base_bytes=base,
        far_bytes=far,
        lists_bytes=lists,
        receiver_bytes=per_receiver,
        keep_lists=bool(keep_lists),
        block_receivers=max(1, block),
        block_bytes=block_bytes,
        own_points=counts.own_points,
        peak_bytes=peak,
        seconds=seconds,
        budget_bytes=budget_bytes,
        time_limit=time_limit,
        fits=bool(fits),
    )


def size_floor(
    counts: SolveCounts, budget_bytes: float | None = None, time_limit: float | None = None
) -> SolveEstimate:
    """The least a solve of ``counts``' size can take: :func:`estimate` with no near triangle, near-field point
    or far-field evaluation per receiver (the sampled counts are ignored). When even this is over a budget,
    the solve is, and the sample that the full estimate needs (the geometry's ordered copy, source tree and
    near grid) need not be built."""
    floor = dataclasses.replace(counts, near_triangles=0.0, near_points=0.0, own_points=0.0, far_evaluations=0.0)
    return dataclasses.replace(estimate(floor, budget_bytes, time_limit, keep_lists=False), least=True)


def check_limits(memory_limit, time_limit) -> None:
    """Refuse a ``memory_limit`` (GB) or ``time_limit`` (s) that is not a positive number, in one sentence."""
    for name, value, unit in (("memory_limit", memory_limit, "GB"), ("time_limit", time_limit, "seconds")):
        if value is None:
            continue
        number = value if isinstance(value, (int, float, np.integer, np.floating)) else float("nan")
        if isinstance(value, bool) or not (math.isfinite(number) and number > 0):
            raise InvalidParameterError(f"{option(name)} must be a positive number of {unit}, got {value!r}.")


def memory_budget(memory_limit: float | None, available: float | None, resident: float = 0.0) -> float | None:
    """Bytes a solve may take: the smaller of the available memory less head-room and ``memory_limit``
    (GB, :data:`GB`) less what the process holds already (``resident``, bytes); None when neither is known."""
    candidates = []
    if available is not None:
        candidates.append(available - max(HEADROOM_FRACTION * available, HEADROOM_BYTES))
    if memory_limit is not None:
        candidates.append(memory_limit * GB - resident)
    return max(0.0, min(candidates)) if candidates else None


def format_bytes(size: float) -> str:
    """``size`` bytes as a short text (``"3.2 GB"``, ``"850 MB"``), in units of 2**30 and 2**20."""
    return f"{size / GB:.1f} GB" if size >= GB else f"{size / 2**20:.0f} MB"


def about(plan) -> str:
    """``"about"``, or ``"at least"`` where ``plan`` (a :class:`SolveEstimate`) is the least a solve of its size takes
    (:func:`size_floor`): the words before its seconds or bytes in a sentence."""
    return "at least" if plan.least else "about"


def bounce_phrase(bounces: int) -> str:
    """``" with its bounce"`` (``" with its 2 bounces"``; nothing for 0): what a light's estimated time holds besides
    its solve."""
    return {0: "", 1: " with its bounce"}.get(bounces, f" with its {bounces} bounces")


def format_seconds(seconds: float) -> str:
    """A duration as a short text (``"40 s"``, ``"12 min"``, ``"3.5 h"``)."""
    if seconds < 10:
        return f"{seconds:.2g} s"
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
