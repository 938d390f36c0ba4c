"""Work off the window's thread: one worker that runs the viewer's solves in order, the latest of each kind.

The window never solves on its own thread (the solver's kernels release the GIL, so the window keeps
drawing and answering while they run). :class:`Jobs` holds at most one waiting job per *kind*: a light
dragged across the view asks for many solves, and only the newest waiting one is run. A job's progress
and its end come back to the window's thread as Qt signals (queued across threads), where the result is
drawn. :meth:`Jobs.cancel` stops the running job at its next progress report by raising :class:`Cancelled`
inside it (the viewer's state puts its settings back, :meth:`ViewerState._solve_with
<translucency.app.viewer.state.ViewerState>`).
"""

from __future__ import annotations

import sys
import threading
import time
import traceback

from PySide6 import QtCore

from ...errors import TranslucencyError

#: Shortest time between two progress signals of one job, s (a solve reports far more often than a bar can show).
PROGRESS_INTERVAL = 0.05


class Cancelled(BaseException):
    """Raised inside a job by its progress report after :meth:`Jobs.cancel` (a BaseException, so that no
    ``except Exception`` of the solver takes it for a fault)."""


class Jobs(QtCore.QObject):
    """One background thread running submitted jobs in order; at most one waiting job per kind.

    Signals (delivered on the thread that made the object, the window's):

    * ``started(kind, label)``: a job began; ``label`` says what it does;
    * ``progress(kind, stage, fraction)``: throttled to one per :data:`PROGRESS_INTERVAL`;
    * ``finished(kind, value)``: the job returned ``value``;
    * ``failed(kind, message)``: the job raised; ``message`` is one sentence (a translucency error's own, or
      the exception's type and text, with the traceback on stderr);
    * ``cancelled(kind)``: the job stopped at :meth:`cancel`;
    * ``idle()``: nothing runs and nothing waits.
    """

    started = QtCore.Signal(str, str)
    progress = QtCore.Signal(str, str, float)
    finished = QtCore.Signal(str, object)
    failed = QtCore.Signal(str, str)
    cancelled = QtCore.Signal(str)
    idle = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self._waiting: dict[str, tuple[str, object]] = {}
        self._condition = threading.Condition()
        self._running: str | None = None
        self._cancel = False
        self._stop = False
        self._last_progress = 0.0
        self._thread = threading.Thread(target=self._loop, name="translucency solves", daemon=True)
        self._thread.start()

    @property
    def busy(self) -> bool:
        """Whether a job runs or waits."""
        with self._condition:
            return self._running is not None or bool(self._waiting)

    @property
    def running(self) -> str | None:
        """The kind of the job that runs now, or None."""
        return self._running

    def submit(self, kind: str, label: str, work) -> None:
        """Run ``work()`` after the jobs before it; a job of the same ``kind`` still waiting is replaced."""
        with self._condition:
            self._waiting.pop(kind, None)
            self._waiting[kind] = (label, work)
            self._condition.notify()

    def cancel(self) -> None:
        """Stop the running job at its next progress report and drop every waiting one."""
        with self._condition:
            self._waiting.clear()
            if self._running is not None:
                self._cancel = True

    def report(self, stage: str, fraction: float) -> None:
        """A running job's progress (called on the worker thread): raises :class:`Cancelled` after
        :meth:`cancel`, else signals ``progress`` now and then."""
        if self._cancel:
            raise Cancelled
        now = time.monotonic()
        if now - self._last_progress >= PROGRESS_INTERVAL or fraction >= 1.0:
            self._last_progress = now
            self.progress.emit(self._running or "", str(stage), float(fraction))

    def wait(self, timeout: float = 60.0) -> bool:
        """Block until nothing runs or waits (tests; the window never waits); False after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while self.busy:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def shutdown(self, timeout: float = 5.0) -> None:
        """Cancel what runs, drop what waits and end the worker (it is a daemon: a solve that does not report in
        ``timeout`` s ends with the process)."""
        with self._condition:
            self._stop = True
            self._waiting.clear()
            if self._running is not None:
                self._cancel = True
            self._condition.notify()
        self._thread.join(timeout)

    def _loop(self) -> None:
        while True:
            with self._condition:
                while not self._waiting and not self._stop:
                    self._condition.wait()
                if self._stop:
                    return
                kind = next(iter(self._waiting))
                label, work = self._waiting.pop(kind)
                self._running, self._cancel = kind, False
            self.started.emit(kind, label)
            try:
                value = work()
            except Cancelled:
                self.cancelled.emit(kind)
            except TranslucencyError as exc:
                self.failed.emit(kind, str(exc))
            except Exception as exc:  # a fault of the program: one line in the window, the traceback on stderr
                traceback.print_exc(file=sys.stderr)
                self.failed.emit(kind, f"{type(exc).__name__}: {exc}")
            else:
                self.finished.emit(kind, value)
            with self._condition:
                self._running = None
                quiet = not self._waiting
            if quiet:
                self.idle.emit()
