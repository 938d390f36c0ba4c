"""Progress on the console: bars on a terminal, one plain line per stage elsewhere, nothing when quiet.

Every command that shows progress (the main job, ``bake``, ``compare``) follows one rule, decided by
:func:`progress_mode` from the stream it writes to (stderr) and ``--quiet``:

========= ======================================================================================
mode      what is written
========= ======================================================================================
``bars``  the stream is a terminal: tqdm bars, redrawn in place
``lines`` a pipe, a file, a CI log: one plain line when a stage ends, e.g.
          ``bunny.ply: far field done (0.41 s)``; never a carriage return or an escape code
``off``   ``--quiet``: no progress at all (warnings and errors still print)
========= ======================================================================================

:class:`StageProgress` is the ``progress(stage, fraction)`` callback of one item (a scan being
solved) in that mode; a stage's time is the wall time spent in it, in seconds. Work that reports a line
of its own (the path tracer's error so far) goes through :func:`throttled_lines` instead.
"""

from __future__ import annotations

import sys
import time

__all__ = ["MODES", "StageProgress", "is_terminal", "progress_mode", "throttled_lines"]

#: The ways progress is shown (module docstring).
MODES = ("bars", "lines", "off")


def is_terminal(stream) -> bool:
    """True when ``stream`` is an open terminal (``isatty``); False for pipes, files and closed streams."""
    isatty = getattr(stream, "isatty", None)
    try:
        return bool(isatty is not None and isatty())
    except (ValueError, OSError):  # a closed stream
        return False


def progress_mode(stream, quiet: bool = False, terminal: bool | None = None) -> str:
    """``"off"`` when ``quiet``, else ``"bars"`` on a terminal and ``"lines"`` elsewhere.

    ``terminal`` overrides the look at ``stream`` (None: :func:`is_terminal`).
    """
    if quiet:
        return "off"
    return "bars" if (is_terminal(stream) if terminal is None else terminal) else "lines"


class StageProgress:
    """The ``progress(stage, fraction)`` callback of one item, shown in a :data:`MODES` mode.

    ``bars``: one tqdm bar ``<name>: <stage>: 42%``, removed when closed. ``lines``: a line
    ``<name>: <stage> done (<seconds> s)`` the first time a stage reaches fraction 1, with the wall
    time spent in that stage (the time between two calls counts for the stage of the later one, so a
    stage that comes back, as with one solve per light direction, adds up to one line). ``off``: nothing.

    Parameters
    ----------
    name : str
        What is being worked on (a file name), the start of every line.
    file : file-like, optional
        Where to write (default: ``sys.stderr`` at the time of each write).
    quiet : bool
        No progress at all.
    terminal : bool, optional
        Force bars (True) or lines (False); None: look at ``file``.
    position : int
        The bar's row among several tqdm bars (0: the top).
    """

    def __init__(self, name: str, file=None, *, quiet: bool = False, terminal: bool | None = None, position: int = 0):
        self.name = name
        self.file = file
        self.position = position
        self.mode = progress_mode(self._stream(), quiet, terminal)
        self.seconds: dict[str, float] = {}
        self._done: set[str] = set()
        self._last = time.perf_counter()
        self._bar = None

    def _stream(self):
        return self.file if self.file is not None else sys.stderr

    def __call__(self, stage: str, fraction: float) -> None:
        """Stage ``stage`` is at ``fraction`` (0 to 1)."""
        now = time.perf_counter()
        if stage in self.seconds:
            self.seconds[stage] += now - self._last
        else:  # the time before a stage's first report is the gap between stages
            self.seconds[stage] = 0.0
        self._last = now
        fraction = min(max(float(fraction), 0.0), 1.0)
        if self.mode == "bars":
            self._draw(stage, fraction)
        elif self.mode == "lines" and fraction >= 1.0 and stage not in self._done:
            self._done.add(stage)
            print(f"{self.name}: {stage} done ({self.seconds[stage]:.2f} s)", file=self._stream(), flush=True)

    def _draw(self, stage: str, fraction: float) -> None:
        from tqdm import tqdm

        if self._bar is None:
            self._bar = tqdm(
                total=100,
                unit="%",
                file=self._stream(),
                position=self.position,
                leave=False,
                dynamic_ncols=True,
                bar_format="{desc}: {percentage:3.0f}%|{bar}|",
            )
        self._bar.set_description_str(f"{self.name}: {stage}", refresh=False)
        self._bar.n = round(100 * fraction)
        self._bar.refresh()

    def close(self) -> None:
        """Remove the bar (bars mode); nothing else to do in the other modes."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> StageProgress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: Seconds between two progress lines of ``translucency reference`` (a trace takes minutes).
REFERENCE_PROGRESS_SECONDS = 15.0


def throttled_lines(seconds: float, prefix: str, file=None):
    """A ``progress(fraction, line)`` callback that prints ``prefix + line`` (to ``file``, default stderr) at
    most every ``seconds`` and at the end."""
    last = [time.perf_counter()]

    def report(fraction: float, line: str) -> None:
        now = time.perf_counter()
        if now - last[0] >= seconds or fraction >= 1.0:
            last[0] = now
            print(prefix + line, file=file if file is not None else sys.stderr, flush=True)

    return report
