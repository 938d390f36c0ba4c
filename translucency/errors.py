"""Exception types of translucency.

Every error that a user can cause (bad parameters, bad files, bad light specifications) is raised as
a subclass of :class:`TranslucencyError` with one sentence that says what is wrong and how to fix it.
The CLI prints that sentence and exits non-zero; it never shows a traceback for these.

A sentence names the setting to change the way the user spelt it: ``--unit m`` in a command-line
run, ``unit='m'`` in a Python call. :func:`option` writes that name; the command line switches it
with :func:`command_line_spelling`.
"""

from __future__ import annotations

import contextlib

# True while a command-line run is in progress (a module global, not a context variable, so that
# the solver's threads and the processes that bake in parallel spell settings the same way).
_command_line = False


def option(keyword: str, value=None) -> str:
    """How a message names a setting: ``--light-dir X`` on the command line, ``light_dir=X`` in Python.

    Parameters
    ----------
    keyword : str
        The Python keyword (``"unit"``, ``"memory_limit"``); the flag is the same with dashes.
    value : optional
        A value to suggest; written as typed on the command line and as a Python literal otherwise.
    """
    if _command_line:
        flag = setting_name(keyword)
        return flag if value is None else f"{flag} {value}"
    return f"{keyword}=" if value is None else f"{keyword}={value!r}"


def setting_name(keyword: str) -> str:
    """A setting as the subject of a sentence: ``--per-direction`` on the command line, ``per_direction`` in Python."""
    return "--" + keyword.replace("_", "-") if _command_line else keyword


def command_line_active() -> bool:
    """True while :func:`option` spells settings as command-line flags (to pass on to worker processes)."""
    return _command_line


@contextlib.contextmanager
def command_line_spelling(enabled: bool = True):
    """Within this block, :func:`option` spells settings as command-line flags."""
    global _command_line
    previous, _command_line = _command_line, enabled
    try:
        yield
    finally:
        _command_line = previous


class TranslucencyError(Exception):
    """Base class of every error translucency raises on purpose.

    ``exit_code`` is the command line's exit status for it: 2 (the run could not start as asked).
    """

    exit_code = 2


class InvalidParameterError(TranslucencyError, ValueError):
    """A physical or numerical parameter is out of its valid range (medium, material, light, solver)."""


class UnknownMaterialError(TranslucencyError, KeyError):
    """A material name that is not in the catalogue."""

    def __str__(self) -> str:  # KeyError would print the message with quotes around it
        return str(self.args[0]) if self.args else ""


class MeshError(TranslucencyError, ValueError):
    """A mesh file or mesh array that cannot be used (unreadable, corrupt, empty, invalid values)."""


class WriteError(TranslucencyError):
    """An output could not be written once the work was done (disk full, quota, read-only file system).

    Nothing is left behind; the command line exits with status 1 (the work ran, its result was lost).
    """

    exit_code = 1


class BudgetError(TranslucencyError):
    """A solve that would need more memory or time than its budget allows (found before the work).

    ``estimate`` holds the :class:`~translucency.scatter.budget.SolveEstimate` that was over budget.
    """

    def __init__(self, message: str, estimate=None):
        super().__init__(message)
        self.estimate = estimate


class DeviceError(TranslucencyError):
    """The GPU could not do its part of a solve (out of its memory, a fault of its driver): the sentence says so and
    names ``--device cpu``; the command line exits with status 1 (the run started as asked)."""

    exit_code = 1


class TranslucencyWarning(UserWarning):
    """Something the user should know that did not stop the work (a coarser solve to fit a budget, say)."""


def warn_user(message: str, category: type[Warning] = TranslucencyWarning) -> None:
    """:func:`warnings.warn` of ``message`` attributed to the first caller outside this package: Python then shows
    the user's own line (``script.py:12``), not the package's source, however deep the warning was raised."""
    import os
    import sys
    import warnings

    package = os.path.dirname(os.path.abspath(__file__)) + os.sep
    frame, level = sys._getframe(1), 2
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)
