"""A call in a child process answers as the call here would: its result, its exception, or a sentence when
the child dies."""

import os

import pytest

from translucency.processes import run_in_child


def test_the_result_comes_back_and_what_the_call_prints_does_not_spoil_it():
    assert run_in_child(divmod, 17, 5) == (3, 2)
    assert run_in_child(print, "printed by the child") is None


def test_the_exception_of_the_call_is_raised_here():
    with pytest.raises(ValueError, match="invalid literal"):
        run_in_child(int, "not a number")


def test_a_child_that_dies_before_it_answers_is_a_child_process_error():
    with pytest.raises(ChildProcessError, match="status 3"):
        run_in_child(os._exit, 3)


def test_the_child_ends_with_its_parent():
    """The child learns its parent's pid; a parent that is already gone ends it at once (status 1)."""
    import subprocess
    import sys

    child = subprocess.run(
        [sys.executable, "-c", "from translucency.processes import _answer; _answer(1)"],
        input=b"",
        capture_output=True,
        timeout=60,
    )
    assert child.returncode == 1


def test_when_one_of_several_children_fails_the_others_are_killed_at_once():
    """run_in_children: the failure is raised, and the child still running (a 30 s sleep) is killed, not
    waited for."""
    import time

    from translucency.processes import run_in_children

    assert run_in_children(divmod, [(17, 5), (9, 4)], at_once=2) == [(3, 2), (2, 1)]
    start = time.perf_counter()
    with pytest.raises(TypeError):
        run_in_children(time.sleep, [(30.0,), ("not a number",)], at_once=2)
    assert time.perf_counter() - start < 15
