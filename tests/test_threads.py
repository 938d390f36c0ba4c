"""translucency.threads.for_ranges: every row once, its progress, and a stop from the progress report."""

import threading

import pytest

from translucency import threads


class _Stop(Exception):
    pass


@pytest.fixture
def two_threads(monkeypatch):
    monkeypatch.setattr(threads, "thread_count", lambda: 2)


def test_every_row_once_and_the_progress_reaches_one(two_threads):
    done, lock, reports = [], threading.Lock(), []

    def kernel(worker, lo, hi):
        with lock:
            done.extend(range(lo, hi))

    threads.for_ranges(kernel, 1000, progress=reports.append)
    assert sorted(done) == list(range(1000))
    assert len(reports) == 64 and max(reports) == 1.0 and min(reports) > 0  # one per range, 32 per thread


def test_a_progress_report_that_raises_stops_the_work(two_threads):
    done, lock = [], threading.Lock()

    def kernel(worker, lo, hi):
        with lock:
            done.extend(range(lo, hi))

    def stop(fraction):
        raise _Stop

    with pytest.raises(_Stop):
        threads.for_ranges(kernel, 6400, progress=stop)
    # each thread stops after the range it was doing: two of the 64
    assert 0 < len(done) <= 2 * 6400 // 64
