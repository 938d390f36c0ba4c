"""Attributes changed for one action and put back as they were when the action fails."""

from __future__ import annotations

import contextlib


@contextlib.contextmanager
def put_back_on_failure(owner, changes: dict, after_undo=None):
    """Set the attributes ``changes`` (name: value) on ``owner`` for the ``with`` block; if the block raises
    (anything, a cancel included), put each back as it was, call ``after_undo()`` when given, and re-raise."""
    before = {name: getattr(owner, name) for name in changes}
    for name, value in changes.items():
        setattr(owner, name, value)
    try:
        yield
    except BaseException:
        for name, value in before.items():
            setattr(owner, name, value)
        if after_undo is not None:
            after_undo()
        raise
