"""numba's on-disk cache of the package's kernels, kept in step with every source they are compiled from.

numba checks a cached kernel against the file that defines it, not against the files of the functions it calls and
compiles into it. After an update in place that changes ``scatter/fits.py`` alone, ``scatter/nearfield.py``'s cached
kernels still hold the old fits (in one such case a scratch tuple of the old length: a segmentation fault). A fresh
clone or install writes every file and compiles afresh; a checkout updated in place keeps the untouched files, and
their caches. :func:`refresh` hashes the sources of the folders that hold kernels (:data:`KERNEL_FOLDERS`) and, in
each folder where numba keeps their kernels, removes them where the hash differs from the one written there before
they were compiled; numba then compiles them again on first use. ``import translucency`` calls it. An edit of any of
those sources therefore compiles every kernel again (a minute or two), where numba alone would compile the edited
module's only, and sometimes run a stale kernel.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["KERNEL_FOLDERS", "STAMP", "cache_folders", "refresh", "sources_digest"]

#: The package's folders whose modules hold numba kernels (and their subfolders): the sources hashed, and the
#: folders whose caches are kept in step with them.
KERNEL_FOLDERS = ("geometry", "reference", "scatter")
#: The file beside the cached kernels that holds the digest of the sources they were compiled from.
STAMP = "translucency-sources.sha256"
#: numba's files of a compiled kernel: its index and one file per compiled signature.
CACHE_SUFFIXES = (".nbi", ".nbc")

PACKAGE = Path(__file__).resolve().parent


def _sources(package: Path) -> list[Path]:
    """The Python sources of ``package``'s :data:`KERNEL_FOLDERS`, in path order."""
    return sorted(path for folder in KERNEL_FOLDERS for path in (package / folder).rglob("*.py"))


def sources_digest(package: Path = PACKAGE) -> str:
    """SHA-256 of the sources of ``package``'s :data:`KERNEL_FOLDERS` (each one's path inside the package, then its
    bytes), in path order."""
    digest = hashlib.sha256()
    for path in _sources(package):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def cache_folders(package: Path = PACKAGE) -> list[Path]:
    """The folders numba keeps the kernels of ``package``'s :data:`KERNEL_FOLDERS` in: ``__pycache__`` beside the
    sources, and under ``NUMBA_CACHE_DIR`` where it is set (numba names a source folder's there by its last part and
    the SHA-1 of its absolute path)."""
    custom = os.environ.get("NUMBA_CACHE_DIR")
    folders = []
    for source in sorted({path.parent.resolve() for path in _sources(package)}):
        folders.append(source / "__pycache__")
        if custom:
            folders.append(Path(custom).resolve() / f"{source.name}_{hashlib.sha1(str(source).encode()).hexdigest()}")
    return folders


def refresh(folders: list[Path] | None = None, digest: str | None = None) -> list[Path]:
    """Remove numba's cached kernels from each of ``folders`` (:func:`cache_folders`) whose :data:`STAMP` is not
    ``digest`` (:func:`sources_digest`), and write the stamp there, making the folder where it is missing (so that it
    is stamped before numba writes a kernel into it): the folders whose kernels were removed. A folder that cannot be
    made, read or written is left as it is (numba then keeps its own checks)."""
    folders = cache_folders() if folders is None else folders
    digest = sources_digest() if digest is None else digest
    cleared = []
    for folder in folders:
        stamp = folder / STAMP
        try:
            if stamp.is_file() and stamp.read_text(encoding="ascii").strip() == digest:
                continue
            folder.mkdir(parents=True, exist_ok=True)
            removed = False
            for entry in folder.iterdir():
                if entry.suffix in CACHE_SUFFIXES:
                    entry.unlink(missing_ok=True)
                    removed = True
            stamp.write_text(digest + "\n", encoding="ascii")
        except (OSError, UnicodeDecodeError):
            continue
        if removed:
            cleared.append(folder)
    return cleared
