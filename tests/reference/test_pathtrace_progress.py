"""The reference's progress: the mean flights of a path estimated while paths are still walking."""

import numpy as np
import pytest

from translucency.reference.trace_settings import expected_flights


def _observe(lengths, starts, now):
    """What the tracer knows at step ``now``: the lengths of the paths finished, the ages of those walking."""
    age = now - starts
    begun = age > 0
    finished = begun & (lengths <= age)
    ended = np.bincount(lengths[finished], minlength=int(lengths.max()) + 1)
    walking = age[begun & ~finished]
    return ended, walking, lengths[finished]


@pytest.mark.parametrize("now", [150, 400, 2000])
def test_a_mixture_of_short_and_long_paths(now):
    rng = np.random.default_rng(5)
    n = 40000
    short = rng.random(n) < 0.6  # out again after a flight or two ...
    lengths = np.where(short, rng.integers(1, 3, n), rng.geometric(1 / 300, n))  # ... or a long walk
    starts = rng.integers(0, 100, n)  # paths begin as the first ones make room
    ended, walking, done = _observe(lengths, starts, now)
    truth = lengths.mean()  # 0.6 * 1.5 + 0.4 * 300 = 120.9
    assert expected_flights(ended, walking) == pytest.approx(truth, rel=0.1)
    if now <= 400:
        assert done.mean() < 0.6 * truth  # the finished paths alone say far too little


def test_nothing_finished_or_walked_yet():
    assert expected_flights(np.zeros(8, dtype=np.int64), np.zeros(0, dtype=np.int64)) == 1.0
    assert expected_flights(np.zeros(8, dtype=np.int64), np.array([3, 5])) >= 6.0  # at least the longest walk
