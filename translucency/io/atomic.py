"""The one atomic writer: every file translucency writes goes through here.

A file is written under a temporary name in its destination folder, flushed to the disk
(``fsync``), renamed over the destination (``os.replace``, atomic on POSIX and Windows) and the
folder is flushed too, so that the rename survives a power cut. A reader sees the old file or the
complete new one, never a part; a write that fails leaves nothing behind.

Temporary names are the tool's own and say who made them::

    .translucency-<pid>-<started>-<host>-<nonce><check>.tmp[.<suffix>]   a file being written
    .translucency-<pid>-<started>-<host>-<nonce><check>.partial          a folder being filled

========= ====================================================================================
field     meaning
========= ====================================================================================
pid       the creating process id
started   when that process started (clock ticks since boot, Linux; 0 where unknown), so that
          a reused process id is not taken for the creator
host      8 hex digits of a hash of the host name: files made on another machine of a shared
          file system are never touched
nonce     8 random hex digits
check     8 hex digits of a keyed hash of the fields before it: a name that merely looks like
          one of these (a user's file, another tool's) does not pass
========= ====================================================================================

Every name is under 100 bytes, whatever the destination's name (file systems allow 255). A process
killed while writing leaves its temporary behind; :func:`sweep` removes the stale ones (made here by
a process that is no longer alive), and the writers below sweep a folder the first time they write
into it in a process, so the next run writing into the same folder cleans up after the killed one.

* :func:`atomic_file` -- a context manager yielding a temporary path for any writer (numpy,
  imageio, VTK, matplotlib) that becomes the destination on success;
* :func:`write_bytes` -- bytes to a file;
* :func:`staged_folder` -- a set of files that replace their namesakes in a folder only when all
  were written;
* :func:`prepare_output_folder`, :func:`prepare_output_file` -- before any work: is the output
  writable? (and the stale temporaries of an earlier run there are swept); :func:`same_file` -- is
  the output the input itself (inputs are never written over)?;
* :func:`write_error` -- the one sentence for an ``OSError`` while writing (disk full, quota,
  read-only file system).
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import re
import secrets
import shutil
import socket
from pathlib import Path

from ..errors import InvalidParameterError, WriteError, option

__all__ = [
    "TEMPORARY_PREFIX",
    "temporary_name",
    "parse_temporary_name",
    "is_stale",
    "sweep",
    "atomic_file",
    "write_bytes",
    "staged_folder",
    "prepare_output_folder",
    "prepare_output_file",
    "same_file",
    "write_error",
]

#: Every temporary file or folder of translucency starts with this.
TEMPORARY_PREFIX = ".translucency-"

_KINDS = ("tmp", "partial")
_NAME = re.compile(
    r"\.translucency-(\d{1,10})-(\d{1,20})-([0-9a-f]{8})-([0-9a-f]{8})([0-9a-f]{8})"
    r"\.(tmp|partial)(\.[A-Za-z0-9]{1,10})?"
)
_KEY = b"translucency temporary name v1"

# folders swept by this process already (a batch writes many files into one folder)
_swept: set[str] = set()


# --------------------------------------------------------------------------------------------------
# names
# --------------------------------------------------------------------------------------------------
def _digest(text: str, size: int = 4) -> str:
    return hashlib.blake2b(text.encode("utf-8", "surrogateescape"), digest_size=size, key=_KEY).hexdigest()


def _host() -> str:
    return _digest(socket.gethostname())


def _start_time(pid: int) -> int | None:
    """When process ``pid`` started (clock ticks since boot); 0 where unknown; None when it is not alive."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as stream:
            fields = stream.read().rsplit(b")", 1)[1].split()
    except FileNotFoundError:
        return None
    except (OSError, IndexError):
        return 0
    if fields[0] in (b"Z", b"X"):  # a zombie: dead, only not yet reaped
        return None
    return int(fields[19])


def _signature(pid: int, started: int, host: str, nonce: str, kind: str) -> str:
    return _digest(f"{pid}-{started}-{host}-{nonce}-{kind}")


def temporary_name(kind: str = "tmp", suffix: str = "") -> str:
    """A fresh temporary name of this process (see the module docstring).

    Parameters
    ----------
    kind : {"tmp", "partial"}
        A file (``tmp``) or a staging folder (``partial``).
    suffix : str
        Appended to a file's name (``".ply"``) for writers that choose the format by the suffix;
        letters and digits only, at most 10.
    """
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, got {kind!r}")
    if suffix and not re.fullmatch(r"\.[A-Za-z0-9]{1,10}", suffix):
        suffix = ""
    pid = os.getpid()
    started = _start_time(pid) or 0
    host, nonce = _host(), secrets.token_hex(4)
    return f"{TEMPORARY_PREFIX}{pid}-{started}-{host}-{nonce}{_signature(pid, started, host, nonce, kind)}.{kind}" + (
        suffix if kind == "tmp" else ""
    )


def parse_temporary_name(name: str) -> dict | None:
    """``{"pid", "started", "host", "kind"}`` of a temporary name made by :func:`temporary_name`, else None.

    A name that has the shape but not the right check digits (one this tool did not make) is None.
    """
    match = _NAME.fullmatch(name)
    if match is None:
        return None
    pid, started, host, nonce, check, kind, _ = match.groups()
    if _signature(int(pid), int(started), host, nonce, kind) != check:
        return None
    return {"pid": int(pid), "started": int(started), "host": host, "kind": kind}


def _alive(pid: int, started: int) -> bool:
    """Is the process that made a temporary still running (the same process, not a reused id)?"""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # it exists, under another user
        pass
    except OSError:
        return True  # cannot tell: keep the file
    now = _start_time(pid)
    if now is None:
        return False
    return not (started and now and now != started)


def is_stale(name: str) -> bool:
    """True for a temporary name of this tool, made on this host, whose process is no longer alive."""
    fields = parse_temporary_name(name)
    return fields is not None and fields["host"] == _host() and not _alive(fields["pid"], fields["started"])


def sweep(folder) -> list[Path]:
    """Remove the stale temporaries of this tool in ``folder`` (not below it); returns what was removed.

    Only names :func:`parse_temporary_name` accepts are considered, only those made on this host by
    a process that is no longer alive are removed, files as files and folders as folders (a link is
    never followed). Errors (a folder that cannot be read, a file that cannot be removed) are
    ignored: sweeping never stops a run.
    """
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(TEMPORARY_PREFIX) or not is_stale(entry.name):
            continue
        kind = parse_temporary_name(entry.name)["kind"]
        try:
            if kind == "tmp" and entry.is_file(follow_symlinks=False):
                os.unlink(entry.path)
            elif kind == "partial" and entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                continue
        except OSError:
            continue
        removed.append(Path(entry.path))
    return removed


def _sweep_once(folder: Path) -> None:
    key = os.path.realpath(folder)
    if key not in _swept:
        _swept.add(key)
        sweep(folder)


# --------------------------------------------------------------------------------------------------
# errors
# --------------------------------------------------------------------------------------------------
_ADVICE = {
    errno.ENOSPC: "the disk is full; free some space or write the output elsewhere",
    errno.EROFS: "the file system is read-only; write the output to a writable disk",
    errno.EACCES: "the folder is not writable; write the output elsewhere",
    errno.EPERM: "the folder is not writable; write the output elsewhere",
    errno.ENAMETOOLONG: "the name is too long for the file system; choose a shorter output name",
}
if hasattr(errno, "EDQUOT"):
    _ADVICE[errno.EDQUOT] = "the disk quota is used up; free some space or write the output elsewhere"


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__


def write_error(path, exc: OSError) -> WriteError:
    """The one-sentence :class:`~translucency.errors.WriteError` for an ``OSError`` while writing ``path``."""
    advice = _ADVICE.get(exc.errno, "check the disk and the output folder")
    return WriteError(f"writing {Path(path).name} failed ({_reason(exc)}): {advice}.")


# --------------------------------------------------------------------------------------------------
# checks before any work
# --------------------------------------------------------------------------------------------------
def _probe(folder: Path, setting: str) -> None:
    """Create and remove a temporary file in ``folder``: a read-only folder or disk shows here."""
    probe = folder / temporary_name()
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    except OSError as exc:
        advice = _ADVICE.get(exc.errno, "check the folder")
        raise InvalidParameterError(
            f"cannot write into {folder} ({_reason(exc)}): {advice} (choose another with {option(setting)})."
        ) from None
    with contextlib.suppress(OSError):
        os.unlink(probe)


def prepare_output_folder(folder, *, create: bool = True, setting: str = "output") -> Path:
    """Check, before any work, that files can be written into ``folder``, and sweep it; create nothing.

    The stale temporaries of this tool (:func:`sweep`) in ``folder`` and in its parent (where
    :func:`staged_folder` stages) are removed.

    Parameters
    ----------
    folder : path-like
        The output folder.
    create : bool
        Whether the folder may be missing (it is created when the files are written); its nearest
        existing parent must then be a writable folder.
    setting : str
        The keyword (or flag) that chose the folder, for the sentence.

    Returns
    -------
    Path

    Raises
    ------
    InvalidParameterError
        A file where the folder (or one of its parents) should be, a missing folder (``create``
        False), or a folder that cannot be written (permissions, a read-only file system).
    """
    folder = Path(folder) if str(folder) else Path(".")
    existing = folder
    while not existing.exists() and existing != existing.parent:
        if not create:
            raise InvalidParameterError(
                f"the folder {folder} does not exist; create it or choose another with {option(setting)}."
            )
        existing = existing.parent
    if not existing.is_dir():
        raise InvalidParameterError(
            f"{existing} is a file, not a folder; choose another output with {option(setting)}."
        )
    _probe(existing, setting)
    for place in (folder, folder.parent):
        if place.is_dir():
            _sweep_once(place)
    return folder


def prepare_output_file(path, *, create_folder: bool = False, setting: str = "output") -> Path:
    """Check, before any work, that ``path`` can be written: its folder (see :func:`prepare_output_folder`)
    and that it is not itself a folder. Returns it as a Path."""
    path = Path(path)
    prepare_output_folder(path.parent if str(path.parent) else Path("."), create=create_folder, setting=setting)
    if path.is_dir():
        raise InvalidParameterError(
            f"{path} is a folder; give {option(setting)} a file name such as "
            f"{path / ('output' + (path.suffix or '.ply'))}."
        )
    return path


def same_file(a, b) -> bool:
    """Whether two paths name the same existing file (through links too); False when either is missing."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


# --------------------------------------------------------------------------------------------------
# writing
# --------------------------------------------------------------------------------------------------
def _fsync(path, flags=os.O_RDONLY if os.name != "nt" else os.O_RDWR) -> None:
    """Flush a file or (POSIX) a folder to the disk."""
    descriptor = os.open(path, flags)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)


def _fsync_folder(folder) -> None:
    """Make renames in ``folder`` durable; a file system that cannot sync folders is not an error."""
    if os.name == "nt":
        return
    with contextlib.suppress(OSError):
        _fsync(folder)


def _remove(path: Path) -> None:
    with contextlib.suppress(OSError):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()


@contextlib.contextmanager
def atomic_file(path, *, keep_suffix: bool = False):
    """Yield a temporary path beside ``path``; on success it replaces ``path`` atomically.

    Write the file at the yielded path (it exists, empty, with the permissions a new file gets;
    an existing destination's permissions are kept). When the block ends without an exception, the
    file is flushed to the disk and renamed over ``path``; otherwise it is removed and the
    destination is left as it was. An ``OSError`` (in the block or while finishing) becomes a
    :class:`~translucency.errors.WriteError` with one sentence.

    Parameters
    ----------
    path : path-like
        The destination; its folder must exist.
    keep_suffix : bool
        End the temporary name with ``path``'s suffix (for writers that choose the format by it).
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    _sweep_once(folder)
    temporary = folder / temporary_name("tmp", path.suffix if keep_suffix else "")
    try:
        os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    except OSError as exc:
        raise write_error(path, exc) from None
    try:
        yield temporary
        _fsync(temporary)
        with contextlib.suppress(FileNotFoundError):
            os.chmod(temporary, os.stat(path).st_mode & 0o7777)
        os.replace(temporary, path)
    except BaseException as exc:
        _remove(temporary)
        if isinstance(exc, OSError):
            raise write_error(path, exc) from None
        raise
    _fsync_folder(folder)


def write_bytes(path, parts) -> Path:
    """Write ``parts`` (bytes, or an iterable of bytes-like objects: a C-contiguous numpy array is written as its
    bytes, without a copy) to ``path`` atomically; returns it."""
    if isinstance(parts, (bytes, bytearray, memoryview)):
        parts = [parts]
    with atomic_file(path) as temporary, open(temporary, "wb") as stream:
        for part in parts:
            stream.write(part)
    return Path(path)


@contextlib.contextmanager
def staged_folder(folder, *, setting: str = "output"):
    """Yield a temporary folder whose files replace their namesakes in ``folder`` when the block succeeds.

    The staging folder lies beside ``folder`` (in its parent, created when missing). On success
    every file in it is flushed to the disk, ``folder`` is created if needed and each file is moved
    in (``os.replace``, atomic per file); on failure ``folder`` is left as it was. The staging
    folder is removed either way. An ``OSError`` becomes a :class:`~translucency.errors.WriteError`.

    Parameters
    ----------
    folder : path-like
        The output folder.
    setting : str
        The keyword (or flag) that chose the folder, for the sentences.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InvalidParameterError(f"{folder} exists and is not a folder; give {option(setting)} a folder name.")
    parent = folder.parent if str(folder.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        _sweep_once(parent)
        staging = parent / temporary_name("partial")
        staging.mkdir()
    except OSError as exc:
        raise write_error(folder, exc) from None
    try:
        yield staging
        files = sorted(staging.iterdir())
        for path in files:
            _fsync(path)
        folder.mkdir(exist_ok=True)
        _sweep_once(folder)
        for path in files:
            os.replace(path, folder / path.name)
        _fsync_folder(folder)
    except OSError as exc:
        raise write_error(folder, exc) from None
    finally:
        _remove(staging)
