"""numba's cache of the package's kernels kept in step with their sources (translucency.kernel_cache)."""

import hashlib
from pathlib import Path

import numba.core.caching
import pytest

from translucency import kernel_cache
from translucency.scatter import fits


def test_the_folders_kept_in_step_are_where_numba_keeps_the_kernels(monkeypatch, tmp_path):
    """Beside the sources (where this checkout's kernels are cached), and under NUMBA_CACHE_DIR by numba's own name for
    a source folder there."""
    assert Path(fits.run_scratch.stats.cache_path).resolve() in kernel_cache.cache_folders()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    numba_name = numba.core.caching._CacheLocator.get_suitable_cache_subpath(fits.__file__)
    assert tmp_path.resolve() / numba_name in kernel_cache.cache_folders()


def test_stale_kernels_are_removed_and_fresh_ones_kept(tmp_path):
    """A folder stamped with other sources loses its kernels (and nothing else); one stamped with these keeps them; a
    folder that is not there yet is made and stamped, before numba writes into it."""
    folder = tmp_path / "__pycache__"
    folder.mkdir()
    for name in ("fits.run_scratch-120.py311.nbi", "fits.run_scratch-120.py311.1.nbc", "fits.cpython-311.pyc"):
        (folder / name).write_bytes(b"x")
    assert kernel_cache.refresh([folder], "one") == [folder]  # no stamp: they may be stale
    assert sorted(p.name for p in folder.iterdir()) == ["fits.cpython-311.pyc", kernel_cache.STAMP]
    (folder / "fits.run_scratch-120.py311.nbi").write_bytes(b"x")
    assert kernel_cache.refresh([folder], "one") == []
    assert (folder / "fits.run_scratch-120.py311.nbi").exists()
    assert kernel_cache.refresh([folder], "two") == [folder]
    assert not (folder / "fits.run_scratch-120.py311.nbi").exists()
    later = tmp_path / "later" / "__pycache__"
    assert kernel_cache.refresh([later], "two") == []
    assert (later / kernel_cache.STAMP).read_text(encoding="ascii").strip() == "two"


def test_the_digest_follows_the_kernels_sources_only(tmp_path):
    """An edit in a folder with kernels changes the digest; one elsewhere in the package does not."""
    for folder in (*kernel_cache.KERNEL_FOLDERS, "app"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "module.py").write_text("x = 1\n")
    before = kernel_cache.sources_digest(tmp_path)
    (tmp_path / "app" / "module.py").write_text("x = 2\n")
    assert kernel_cache.sources_digest(tmp_path) == before
    (tmp_path / "scatter" / "module.py").write_text("x = 2\n")
    assert kernel_cache.sources_digest(tmp_path) != before
    assert len(before) == len(hashlib.sha256().hexdigest())


@pytest.mark.parametrize("path", sorted(kernel_cache.PACKAGE.rglob("*.py")), ids=lambda p: p.name)
def test_every_module_with_cached_kernels_is_in_a_kernel_folder(path):
    """A module outside KERNEL_FOLDERS whose kernels numba caches would not be kept in step."""
    if "cache=True" in path.read_text(encoding="utf-8"):
        assert path.relative_to(kernel_cache.PACKAGE).parts[0] in kernel_cache.KERNEL_FOLDERS
