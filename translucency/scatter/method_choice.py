"""Method ``auto``: ``tree`` for a surface's first lights, relighting's operators once those lights have paid for them.

A light solved by ``tree`` (docs/physics.md §8.3) costs about the same every time. Relighting's operators (§8.7,
§8.9) cost tens of ``tree`` solves to prepare and then a small share of one per light. Which is faster depends on how
many lights are still to come, which the solver cannot know. ``auto`` follows the rent-or-buy rule (docs/physics.md
§8.10): it solves by ``tree`` until the lights it solved so on one surface, medium, model and ``tol`` have taken as
long as the budget's estimate of preparing the operators, then prepares them, where they fit the memory and time
limits. Its time is then never much more than twice that of the better of the two methods chosen in hindsight, for
any number of lights.

What it keeps per surface (a :class:`Tally` per operator key, :func:`~translucency.scatter.relight.operator_key`, on
the spatially ordered surface, where relighting keeps its operators) is dropped with the surface. Preparing one set of
operators starts every other key's count again, so that lights that take turns between two media cannot prepare and
replace operators at every light.

``auto`` holds ``tol``: operators whose first light is :data:`~translucency.scatter.relight.AUTO_KEEP_SHARE` ``tol``
or more off a ``tree`` solve of it at the 99th percentile (relighting's fits and far field at dark vertices miss it in
some media, docs/physics.md §8.7, §8.9, and one light's check does not bound another's) are given up, and every later
light of those settings on that surface is solved by ``tree``; so are lights whose settings have operators held, made
by method ``relight``, that miss that share of ``tol``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from . import relight
from .gpu.probe import pair_device
from .names import check_device
from .solve import relight_estimate
from .surface import PerSurface, spatial_order

__all__ = [
    "AUTO",
    "ESTIMATE_AFTER",
    "Tally",
    "chosen_method",
    "count_light",
    "missed_tol",
    "operators_held",
    "refuse",
    "tally_of",
]

#: The name of the method this module chooses for.
AUTO = "auto"
#: Lights solved by ``tree`` before the operators' cost is estimated: the estimate (the near lists and the crosses of
#: a sample of the far blocks) takes about as long as a light on the default bunny, so it waits until it is small
#: beside the lights' time, and is counted in it.
ESTIMATE_AFTER = 3


@dataclass
class Tally:
    """The lights ``auto`` solved by ``tree`` on one surface for one operator key.

    Attributes
    ----------
    lights : int
        The lights solved by ``tree``.
    seconds : float
        Their time, with the estimate's own, s.
    preparation : float or None
        The operators' estimated preparation, s (None before it is made).
    refused : str or None
        Why the operators will not be prepared (a sentence; None while they may).
    limits : tuple or None
        The memory (GB) and time (s) limits the estimate and the refusal hold for (other limits estimate again).
    """

    lights: int = 0
    seconds: float = 0.0
    preparation: float | None = None
    refused: str | None = None
    limits: tuple | None = None

    def as_dict(self) -> dict:
        """The tally as plain numbers (``stats["method_choice"]``)."""
        return {
            "tree_lights": self.lights,
            "tree_seconds": self.seconds,
            "preparation_estimate_s": self.preparation,
            "refused": self.refused,
        }


_TALLIES = PerSurface("method auto's tally", counted=False)
#: Per surface and operator key, why ``auto`` prepares no operators again: their first light missed
#: ``relight.AUTO_KEEP_SHARE`` of ``tol`` (a sentence; kept while the surface is, through other keys' preparations).
_MISSED = PerSurface("operators that missed tol", counted=False)


def _device(device: str) -> str:
    """Where relighting would sum its far field for the setting ``device``: ``cpu`` or ``gpu``."""
    return pair_device(check_device(device), "relight")[0]


def _key(medium, model: str, tol: float, device: str) -> tuple:
    """The operator key of these settings, on the device relighting would sum its far field on."""
    return relight.operator_key(medium, model, tol, _device(device))


def tally_of(surface, medium, model: str, tol: float, device: str) -> Tally:
    """The :class:`Tally` of ``surface`` for these settings (a new one where none was kept)."""
    return _TALLIES.get(_ordered(surface), _key(medium, model, tol, device), Tally)


def _ordered(surface):
    """The spatially ordered surface the solver works on and relighting keeps its operators on."""
    return spatial_order(surface)[0]


def chosen_method(
    surface, medium, model: str, tol: float, device: str, memory_limit=None, time_limit=None, *, varying=False
) -> str:
    """``"tree"`` or ``"relight"``: what ``auto`` solves this light of ``surface`` (the spatially ordered surface, mm)
    by, for the medium (1/mm), model, ``tol`` and device. ``relight`` where the surface keeps operators for them, or
    where the lights solved by ``tree`` have taken at least the operators' estimated preparation (s) and the operators
    fit ``memory_limit`` (GB) and ``time_limit`` (s); ``tree`` otherwise, and always with a reflectance per vertex
    (``varying``: one medium per level, whose operators would replace each other)."""
    if varying:
        return "tree"
    surface, key = _ordered(surface), _key(medium, model, tol, device)
    tally = _TALLIES.get(surface, key, Tally)
    missed = _MISSED.peek(surface, key)
    if missed is not None:
        tally.refused = missed
        return "tree"
    held = relight.kept_operator(surface, key)
    if held is not None:
        # made by method relight, which keeps them up to 10 tol
        over = held.stats.get("checked_p99", 0.0) >= relight.AUTO_KEEP_SHARE * tol
        return "tree" if isinstance(held, relight.TreeInstead) or over else "relight"
    if tally.limits != (memory_limit, time_limit):  # the estimate and any refusal were for other limits
        tally.preparation, tally.refused, tally.limits = None, None, (memory_limit, time_limit)
    if tally.refused is not None or tally.lights < ESTIMATE_AFTER:
        return "tree"
    if tally.preparation is None:
        start = time.perf_counter()
        plan, _ = relight_estimate(surface, medium, model, tol, _device(device), memory_limit, time_limit)
        tally.seconds += time.perf_counter() - start
        if not plan.fits:
            tally.refused = "the operators would be over the budget"
            return "tree"
        tally.preparation = float(plan.seconds)
    return "relight" if tally.seconds >= tally.preparation else "tree"


def operators_held(surface, medium, model: str, tol: float, device: str) -> bool:
    """Whether ``surface`` keeps relighting's operators (or their :class:`~translucency.scatter.relight.TreeInstead`)
    for these settings."""
    return relight.kept_operator(_ordered(surface), _key(medium, model, tol, device)) is not None


def count_light(surface, medium, model: str, tol: float, device: str, method: str, seconds: float) -> Tally:
    """Count a light that ``auto`` solved in ``seconds`` by ``method``: ``tree`` (its tally grows) or ``prepared``
    (operators made for it: every tally of ``surface`` starts again). Returns the tally of these settings."""
    surface, key = _ordered(surface), _key(medium, model, tol, device)
    if method == "tree":
        tally = _TALLIES.get(surface, key, Tally)
        tally.lights += 1
        tally.seconds += seconds
        return tally
    held = _TALLIES.peek(surface, key)
    _TALLIES.drop(surface)
    return held or Tally()


def missed_tol(surface, medium, model: str, tol: float, device: str, p99: float, counted: Tally) -> Tally:
    """Prepare no operators of these settings on ``surface`` again: their first light was ``p99`` (relative) off a
    ``tree`` solve of it at the 99th percentile, not under :data:`~translucency.scatter.relight.AUTO_KEEP_SHARE`
    ``tol``. ``counted`` is the tally :func:`count_light` gave
    back for that light (preparing dropped it); it is kept again with the light as one more ``tree`` light (its answer
    is the check's ``tree`` solve), and returned."""
    ordered, key = _ordered(surface), _key(medium, model, tol, device)
    reason = (
        f"relighting's operators were {100 * p99:.3g} % off tree at their first light (99th percentile), "
        f"not under {relight.AUTO_KEEP_SHARE:g} of the tolerance of {100 * tol:.2g} % (another light may be "
        "further off)"
    )
    _MISSED.get(ordered, key, lambda: reason)
    tally = _TALLIES.get(ordered, key, lambda: counted)
    tally.lights += 1
    tally.refused = reason
    return tally


def refuse(surface, medium, model: str, tol: float, device: str, reason: str, limits: tuple) -> None:
    """Prepare no operators of these settings on ``surface`` while the memory and time ``limits`` (GB, s) stay as they
    are (``reason``: why, a sentence)."""
    tally = tally_of(surface, medium, model, tol, device)
    tally.refused, tally.limits = reason, limits
