"""What a path tracing may be asked: the paths per vertex, the seed, and the time its paths would take.

Each check is one sentence naming the setting (and its command-line flag), before or, for the time, once the first
paths have told the rate, long before the rest is traced.
"""

from __future__ import annotations

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
    its work in ``elapsed`` seconds), naming the ``spp`` that would fit."""
    projected = elapsed / max(done, 1e-9)
    if projected <= time_limit:
        return
    fits = int(spp * time_limit / projected)
    advice = f"lower --spp to {fits}" if fits >= 2 else "trace a smaller mesh or a proxy of it"
    raise BudgetError(
        f"--spp {spp} would take about {format_seconds(projected)} at the rate of the first paths, over the time "
        f"limit of {format_seconds(time_limit)}; {advice}, or raise --time-limit."
    )
