"""The first-run notice (real compilation only) and the set-up's warm-up of the solver's kernels."""

import json
import os
import subprocess
import sys

import numba
import pytest

from translucency.app import warmup
from translucency.threads import thread_count


def _compiled_function(module):
    def f(x):
        return x + 1

    f.__module__ = module
    return numba.njit(f)


def test_notice_is_said_once_and_only_for_our_own_kernels():
    said = []
    with warmup.compile_notice(lambda: said.append(1)):
        _compiled_function("elsewhere.module")(1)
        _compiled_function("translucency_plugin.fake")(1)  # another package
        assert said == []
        _compiled_function("translucency.io.fake")(1)  # the cleaning's kernels count too
        _compiled_function("translucency.scatter.fake")(2.0)
    assert said == [1]
    _compiled_function("translucency.scatter.fake")(1)  # outside the block: nothing listens
    assert said == [1]


def test_notice_is_silent_when_nothing_compiles():
    kernel = _compiled_function("translucency.scatter.fake")
    kernel(1)
    said = []
    with warmup.compile_notice(lambda: said.append(1)):
        kernel(3)  # already compiled for int64
    assert said == []


@pytest.mark.slow
def test_warm_up_fills_the_cache_in_numba_cache_dir_once(tmp_path):
    """An empty NUMBA_CACHE_DIR: the warm-up says it compiles and fills it; the second run finds every
    kernel of the main job in the cache, compiles nothing and prints nothing."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    command = [sys.executable, "-m", "translucency.app.warmup"]
    first = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    assert first.stdout.count(warmup.NOTICE) == 1 and "ready" in first.stdout
    assert any((tmp_path / "cache").rglob("*.nbi"))
    second = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    assert second.returncode == 0 and second.stdout == ""
    check = subprocess.run(
        [sys.executable, "-c", "from translucency.app.warmup import cold_kernels; print(cold_kernels())"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert check.stdout.strip() == "[]"
    empty = subprocess.run(
        [sys.executable, "-c", "from translucency.app.warmup import cold_kernels; print(len(cold_kernels()))"],
        env={**env, "NUMBA_CACHE_DIR": str(tmp_path / "other")},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert int(empty.stdout) == len(warmup.MAIN_JOB_KERNELS)


# Run as the set-up runs it (``python -m translucency.app.warmup``, so the module is ``__main__``) in a fresh process
# on an empty cache: numba's compilations in the first process, and whether every kernel of the main job is cached
# afterwards.
_TRACED_WARM_UP = """
import json, runpy
from numba.core import event
compiled = []
class Listener(event.Listener):
    def on_start(self, ev):
        dispatcher = (ev.data or {}).get("dispatcher")
        compiled.append(getattr(getattr(dispatcher, "py_func", None), "__qualname__", ""))
    def on_end(self, ev):
        pass
event.register("numba:compile", Listener())
try:
    runpy.run_module("translucency.app.warmup", run_name="__main__")
except SystemExit:
    pass
from translucency.app.warmup import cold_kernels
print(json.dumps(sorted(set(compiled))))
print(json.dumps(cold_kernels()))
"""


@pytest.mark.slow
@pytest.mark.skipif(thread_count() < 2, reason="one core: the warm-up compiles in one process")
def test_relighting_kernels_are_compiled_by_the_second_process_and_found_by_the_first(tmp_path):
    """Run as the set-up runs it, the warm-up's second process compiles relighting's own kernels (its operators and
    their product), and the first finds them in the cache: it compiles none of them itself, says nothing of the
    second, and afterwards no kernel of the main job is cold."""
    from translucency.scatter import lowrank, relight

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    run = subprocess.run([sys.executable, "-c", _TRACED_WARM_UP], env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "second compiling process" not in run.stderr, run.stderr
    compiled, cold = (json.loads(line) for line in run.stdout.strip().splitlines()[-2:])
    assert cold == []
    own = {kernel.py_func.__qualname__ for kernel in (*relight.RELIGHT_KERNELS, *lowrank.LOW_RANK_KERNELS)}
    own.add("_operator_rows")  # the near field's operator, which only relighting makes
    assert own.isdisjoint(compiled), compiled
    assert "_grouped_rows_directional" in compiled  # the first process did compile tree's kernels
