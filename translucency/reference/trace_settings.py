"""What a path tracing may be asked: the paths per vertex, the seed, and the time its paths would take (from the
share of its work done, :class:`WorkTally`).

Each check is one sentence naming the setting (and its command-line flag), before or, for the time, once the first
paths have told the rate, long before the rest is traced.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import BudgetError, InvalidParameterError
from ..scatter.budget import format_seconds

__all__ = ["check_seed", "check_spp", "check_time"]


def check_spp(spp) -> int:
    """``spp`` as an int of at least 2 (a standard error needs two paths), or a sentence naming ``spp``/``--spp``."""
    if isinstance(spp, bool) or not isinstance(spp, (int, np.integer)) or spp < 2:
        raise InvalidParameterError(f"spp (--spp) must be an integer of at least 2 paths per vertex, got {spp!r}.")
    return int(spp)


def check_seed(seed) -> int:
    """``seed`` as an int of at least 0 (what NumPy's generators take), or a sentence naming ``seed``/``--seed``."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError(f"seed (--seed) must be an integer of at least 0, got {seed!r}.")
    return int(seed)


def check_time(time_limit: float, elapsed: float, done: float, spp: int) -> None:
    """Refuse the tracing when it would take longer than ``time_limit`` at the rate so far (the share ``done`` of
    its work in ``elapsed`` seconds), naming the ``spp`` that would fit. ``done`` should be the largest share the
    paths so far allow (:meth:`WorkTally.share` with ``largest=True``): a tracing is refused only when even that
    says it would not fit."""
    projected = elapsed / max(done, 1e-9)
    if projected <= time_limit:
        return
    fits = int(spp * time_limit / projected)
    advice = f"lower --spp to {fits}" if fits >= 2 else "trace a mesh with fewer vertices"
    raise BudgetError(
        f"--spp {spp} would take at least {format_seconds(projected)} at the rate of the paths so far, over the time "
        f"limit of {format_seconds(time_limit)}; {advice}, or raise --time-limit."
    )


def expected_flights(ended, ages, tail: bool = True) -> float:
    """Mean flights of a path, from the paths finished so far and those still walking (Kaplan-Meier).

    ``ended[a]`` paths finished after ``a`` flights; ``ages`` are the flights of the paths still walking (they
    will make at least one more). The hazard at ``a`` is ``ended[a]`` over the paths that reached ``a``
    flights; the survival ``S(a)`` is the product of one minus the hazards up to ``a``, and the mean is
    ``sum_a S(a)``, continued past the longest walk so far as if the hazard of its last tenth held on
    (geometric; ``tail=False``: not continued, the least mean the paths so far allow). Short paths (out again
    near where they entered) finish first and long ones are still walking: the mean of the finished lengths
    alone would be far too short, and a share of paths finished far ahead of the time. Early on, the few paths
    finished late make the continued tail uncertain by orders of magnitude.
    """
    ages = np.asarray(ages, dtype=np.int64)
    top = max(int(np.flatnonzero(ended).max(initial=0)), int(ages.max(initial=0)))
    if top == 0:
        return 1.0
    counted = np.zeros(top + 1)  # walking paths may be older than any finished one: ended is shorter then
    counted[: min(len(ended), top + 1)] = np.asarray(ended[: top + 1], dtype=np.float64)
    walking = np.bincount(ages, minlength=top + 1)[: top + 1].astype(np.float64)
    # reached[a]: paths that made at least a flights (finished at a or later, or walking at age a or more)
    reached = np.cumsum((counted + walking)[::-1])[::-1]
    hazard = np.divide(counted, reached, out=np.zeros_like(counted), where=reached > 0)
    survival = np.cumprod(1.0 - hazard[1:])  # S(a) for a = 1 .. top; S(0) = 1
    beyond = 0.0
    if tail:
        last = hazard[max(1, int(0.9 * top)) :]
        tail_hazard = float(last[last > 0].mean()) if np.any(last > 0) else 0.0
        beyond = survival[-1] * (1.0 / tail_hazard - 1.0) if tail_hazard > 0 else 0.0
    return float(1.0 + survival[:-1].sum() + survival[-1] + beyond)


class WorkTally:
    """A tracing's work as it goes: the flights simulated so far (one per path in flight per step) and how many
    flights each finished path took (``ended[a]``: paths that finished after ``a`` flights)."""

    def __init__(self):
        self.flights = 0
        self.ended = np.zeros(64, dtype=np.int64)

    def add(self, lengths) -> None:
        """Paths that finished after ``lengths`` flights each."""
        lengths = np.asarray(lengths, dtype=np.int64)
        if lengths.size and lengths.max() >= self.ended.size:
            grown = np.zeros(2 * int(lengths.max()) + 1, dtype=np.int64)
            grown[: self.ended.size] = self.ended
            self.ended = grown
        self.ended += np.bincount(lengths, minlength=self.ended.size)

    def share(self, finished: int, n_paths: int, ages, largest: bool = False) -> float:
        """The share of the work done: the flights so far over ``n_paths`` times the mean flights of a path
        (:func:`expected_flights`, from the paths finished and those walking, of ``ages`` flights so far); 1 only
        when every path has finished. ``largest``: the largest share the paths so far allow (the mean not
        continued past the longest walk), what a refusal is judged on."""
        if finished >= n_paths:
            return 1.0
        mean = expected_flights(self.ended, ages, tail=not largest)
        return min(self.flights / (n_paths * mean), 0.99)


def progress_line(done: float, elapsed: float, samples: int, median_error: float) -> str:
    """``"37 % of the work, 12 s; median error 3.1 % after 24 paths per point"`` for a tracing's progress callback
    (the work: the flights expected in all, :class:`WorkTally`; the error once it is known, else left out)."""
    line = f"{100 * done:.0f} % of the work, {elapsed:.0f} s"
    if samples >= 2 and math.isfinite(median_error):
        line += f"; median error {100 * median_error:.1f} % after {samples} paths per point"
    return line
