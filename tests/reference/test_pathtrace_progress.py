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


def test_paths_walking_longer_than_any_finished_one_are_counted():
    """A path still walking may be older than the tally of finished lengths is long (the tracing crashed there on
    every bunny): it counts as having reached its age."""
    ended = np.zeros(64, dtype=np.int64)
    ended[[1, 2, 40]] = [500, 300, 10]
    walking = np.array([70, 120, 2079])
    assert expected_flights(ended, walking, tail=False) >= 2.0
    assert expected_flights(ended, walking) >= expected_flights(ended, walking, tail=False)


@pytest.mark.parametrize("now", [20, 60, 150, 400])
def test_the_mean_without_its_tail_is_never_above_the_truth(now):
    """What a refusal is judged on (``tail=False``): the least mean the paths so far allow, below the true mean
    at every moment, while the continued tail may overshoot it early on."""
    rng = np.random.default_rng(7)
    n = 40000
    short = rng.random(n) < 0.6
    lengths = np.where(short, rng.integers(1, 3, n), rng.geometric(1 / 300, n))
    starts = rng.integers(0, 100, n)
    ended, walking, _ = _observe(lengths, starts, now)
    assert expected_flights(ended, walking, tail=False) <= lengths.mean()
