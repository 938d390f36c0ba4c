"""The atomic writer: names it recognises as its own, sweeping only stale ones, writes that fail cleanly."""

import errno
import os
import subprocess
import sys

import pytest

from translucency.errors import InvalidParameterError, WriteError
from translucency.io import atomic


def names_of_a_dead_process(*kinds):
    """Temporary names made by a process that has ended (one per kind)."""
    code = (
        "import sys; from translucency.io.atomic import temporary_name; "
        "print(' '.join(temporary_name(k) for k in sys.argv[1:]))"
    )
    return subprocess.run(
        [sys.executable, "-c", code, *kinds], check=True, capture_output=True, text=True
    ).stdout.split()


def test_names_carry_the_pid_and_stay_short_and_are_recognised():
    name = atomic.temporary_name()
    assert name.startswith(f".translucency-{os.getpid()}-") and name.endswith(".tmp")
    assert len(name.encode()) < 100 and len(atomic.temporary_name("tmp", ".ply").encode()) < 100
    fields = atomic.parse_temporary_name(name)
    assert fields["pid"] == os.getpid() and fields["kind"] == "tmp"
    assert atomic.parse_temporary_name(atomic.temporary_name("partial"))["kind"] == "partial"
    assert not atomic.is_stale(name)  # this process is alive


def test_a_name_that_merely_looks_like_ours_is_not_ours():
    name = atomic.temporary_name()
    forged = name[:-5] + ("0" if name[-5] != "0" else "1") + name[-4:]  # the last check digit changed
    assert atomic.parse_temporary_name(forged) is None
    assert atomic.parse_temporary_name(".translucency-123-0-abcdef01-0123456789abcdef.tmp") is None
    assert atomic.parse_temporary_name(".bunny.ply.x1y2z3.tmp") is None


def test_sweep_removes_only_stale_temporaries_of_this_tool(tmp_path):
    dead_file, dead_folder = names_of_a_dead_process("tmp", "partial")
    (tmp_path / dead_file).write_bytes(b"x" * 1000)
    (tmp_path / dead_folder).mkdir()
    (tmp_path / dead_folder / "grid.png").write_bytes(b"png")
    alive = atomic.temporary_name()
    (tmp_path / alive).write_bytes(b"being written")
    others = [
        ".bunny_marble.ply.abc123.tmp",
        ".out.q1w2e3.partial",
        ".translucency-1-0-00000000-0000000000000000.tmp",
        "notes.txt",
        dead_file[:-4] + ".partial",
    ]  # the last: the right shape, the check of another kind
    for name in others:
        (tmp_path / name).write_bytes(b"not ours")
    removed = atomic.sweep(tmp_path)
    assert sorted(p.name for p in removed) == sorted([dead_file, dead_folder])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(others + [alive])


def test_a_file_of_another_host_is_never_swept(tmp_path, monkeypatch):
    (dead,) = names_of_a_dead_process("tmp")
    (tmp_path / dead).write_bytes(b"x")
    monkeypatch.setattr(atomic.socket, "gethostname", lambda: "another-machine")
    assert atomic.sweep(tmp_path) == [] and (tmp_path / dead).exists()


def test_the_first_write_into_a_folder_sweeps_it(tmp_path):
    (dead,) = names_of_a_dead_process("tmp")
    (tmp_path / dead).write_bytes(b"x" * 100)
    atomic.write_bytes(tmp_path / "a.bin", [b"one", b"two"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.bin"]
    assert (tmp_path / "a.bin").read_bytes() == b"onetwo"


def test_a_240_character_stem_is_written(tmp_path):
    path = tmp_path / ("s" * 240 + ".ply")
    atomic.write_bytes(path, b"data")
    assert path.read_bytes() == b"data" and os.listdir(tmp_path) == [path.name]


@pytest.mark.parametrize(
    "code, words",
    [
        (errno.ENOSPC, "the disk is full"),
        (errno.EROFS, "read-only"),
        (getattr(errno, "EDQUOT", errno.ENOSPC), "free some space"),
    ],
)
def test_a_failed_write_is_one_sentence_and_leaves_the_old_file(tmp_path, monkeypatch, code, words):
    path = tmp_path / "out.ply"
    path.write_bytes(b"old")

    def fail(*args):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(atomic, "_fsync", fail)
    with pytest.raises(WriteError) as caught:
        atomic.write_bytes(path, b"new")
    message = str(caught.value)
    assert message.startswith("writing out.ply failed (") and words in message and message.endswith(".")
    assert "\n" not in message and caught.value.exit_code == 1
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["out.ply"]


def test_a_failed_staged_folder_leaves_nothing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(RuntimeError):
        with atomic.staged_folder(out) as staging:
            (staging / "a.txt").write_text("a")
            raise RuntimeError("stop")
    assert os.listdir(tmp_path) == []
    with atomic.staged_folder(out) as staging:
        (staging / "a.txt").write_text("a")
    assert os.listdir(tmp_path) == ["out"] and os.listdir(out) == ["a.txt"]


def test_outputs_that_cannot_be_written_are_found_before_any_work(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(InvalidParameterError, match="is a file, not a folder"):
        atomic.prepare_output_folder(tmp_path / "file" / "sub")
    with pytest.raises(InvalidParameterError, match="does not exist"):
        atomic.prepare_output_folder(tmp_path / "missing", create=False)
    with pytest.raises(InvalidParameterError, match="is a folder"):
        atomic.prepare_output_file(tmp_path)
    assert atomic.prepare_output_folder(tmp_path / "new" / "deeper") == tmp_path / "new" / "deeper"
    assert sorted(os.listdir(tmp_path)) == ["file"]  # nothing created, no probe left
