"""Child processes that end with their parent, and library calls run in one.

Batch bakes start worker processes (:mod:`translucency.app.bake`), and a library call that keeps its memory
after it returns (fast-simplification's module-level mesh: :func:`translucency.io.decimate.simplify_arrays`)
runs in a child of its own, whose memory goes back to the system when it ends. Either way the child must
not outlive this process, even when this process is killed (:func:`end_with_parent`).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from pathlib import Path

__all__ = [
    "available_cores",
    "child_pool",
    "descendants",
    "end_with_parent",
    "run_in_child",
    "run_in_children",
    "WATCHDOG_INTERVAL_S",
]


def available_cores() -> int:
    """CPU cores this process may run on (its affinity where the platform tells it, else the machine's)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on every platform
        return max(1, os.cpu_count() or 1)


def run_in_children(function, argument_lists, at_once: int) -> list:
    """``function(*args)`` for every ``args`` of ``argument_lists``, each in a child process of its own
    (:func:`run_in_child`), at most ``at_once`` at a time: their results in order.

    When one of them fails, or this process is interrupted (Ctrl-C), the children still running are killed and
    those not started yet are not started; the first failure (or the interrupt) is raised.
    """
    from concurrent.futures import FIRST_EXCEPTION, wait

    with child_pool(at_once) as (pool, started):
        futures = [pool.submit(run_in_child, function, *args, started=started) for args in argument_lists]
        wait(futures, return_when=FIRST_EXCEPTION)  # the first failure, not the first call's end, is raised
        for future in futures:
            if future.done() and future.exception() is not None:
                raise future.exception()
        return [future.result() for future in futures]


@contextlib.contextmanager
def child_pool(at_once: int):
    """``(pool, started)``: a thread pool of ``at_once`` threads, each waiting for one child
    (``pool.submit(run_in_child, ..., started=started)``). When the block raises or is interrupted, the children
    still running are killed and the calls not started are dropped."""
    from concurrent.futures import ThreadPoolExecutor

    started: list = []  # every child's Popen, killed together
    pool = ThreadPoolExecutor(max_workers=max(1, int(at_once)))
    try:
        yield pool, started
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        for child in list(started):
            with contextlib.suppress(OSError):
                child.kill()
        raise
    finally:
        pool.shutdown(wait=True)


def run_in_child(function, *args, started: list | None = None):
    """``function(*args)`` in a new Python process that ends with this one (:func:`end_with_parent`): its
    result, or the exception it raised, raised here.

    ``function`` must be importable by name (a module-level function), its arguments and result picklable.
    The child is ``python -c`` with the arguments on its standard input and the answer on its standard
    output, not :mod:`multiprocessing`: a spawned process imports the caller's main script again, which a
    script without an ``if __name__ == "__main__"`` guard does not survive. What the call prints goes to
    standard error.

    ``started``: a list the child's :class:`subprocess.Popen` is appended to as it starts (for
    :func:`run_in_children`, which kills them together).

    Raises
    ------
    ChildProcessError
        The child ended without an answer (killed, out of memory).
    """
    import pickle
    import subprocess

    child = subprocess.Popen(
        [sys.executable, "-c", f"from {__name__} import _answer; _answer({os.getpid()})"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
    )
    if started is not None:
        started.append(child)
    try:
        with contextlib.suppress(BrokenPipeError):  # a child that died at once: said below
            pickle.dump((function.__module__, function.__qualname__, args), child.stdin, protocol=5)
        with contextlib.suppress(BrokenPipeError):
            child.stdin.close()
        try:
            failed, value = pickle.load(child.stdout)
        except (EOFError, pickle.UnpicklingError):
            child.wait()
            raise ChildProcessError(
                f"the child process ended with status {child.returncode} before it answered"
            ) from None
    except BaseException:  # interrupted here, or no answer: the child goes too
        child.kill()
        raise
    finally:
        child.stdout.close()
        child.wait()
    if failed:
        raise value
    return value


def _answer(parent: int) -> None:
    """The child of :func:`run_in_child`: read the call from standard input, write ``(failed, value)``."""
    import importlib
    import pickle

    end_with_parent(parent)
    answer = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # what the call prints goes to standard error, not into the answer
    module, name, args = pickle.load(sys.stdin.buffer)
    try:
        function = importlib.import_module(module)
        for part in name.split("."):
            function = getattr(function, part)
        result = (False, function(*args))
    except Exception as exc:  # noqa: BLE001 -- handed to the caller, who raises it
        result = (True, exc)
    pickle.dump(result, answer, protocol=5)
    answer.close()


#: Seconds between two looks of a worker's watchdog at its parent.
WATCHDOG_INTERVAL_S = 0.5

_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def end_with_parent(parent: int) -> None:
    """Make this process (and the processes it starts) end when process ``parent`` ends.

    On Linux the kernel kills this process the moment its parent dies (``prctl(PR_SET_PDEATHSIG,
    SIGKILL)``, through ctypes), even while a numba kernel holds the GIL. Everywhere a watchdog
    thread also looks at ``os.getppid()`` every :data:`WATCHDOG_INTERVAL_S` s; when the parent is
    gone it kills this process's own children, then this process. A parent that died before this
    call is noticed at once.

    Parameters
    ----------
    parent : int
        The pid of the parent process this one must not outlive.
    """
    import threading

    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # no prctl here: the watchdog alone
            pass
    if os.getppid() != parent:  # the parent died before the signal was armed
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent,), name="translucency-watchdog", daemon=True).start()


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(WATCHDOG_INTERVAL_S)
        if os.getppid() != parent:
            for child in descendants(os.getpid()):
                with contextlib.suppress(OSError):
                    os.kill(child, signal.SIGKILL)
            os._exit(1)


def descendants(pid: int) -> list[int]:
    """Every descendant of process ``pid`` (Linux ``/proc``; empty elsewhere)."""
    parents = {}
    for entry in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            parents[int(entry.parent.name)] = int(entry.read_bytes().rsplit(b")", 1)[1].split()[1])
    found, frontier = [], [pid]
    while frontier:
        frontier = [child for child, parent in parents.items() if parent in frontier]
        found += frontier
    return found
