"""The pymeshlab import check: a clear sentence when the OpenGL-dependent filters are missing."""

import sys
import types

import pytest

from translucency.errors import TranslucencyError
from translucency.io.meshlab import import_pymeshlab


def test_real_pymeshlab_has_the_filters():
    pymeshlab = import_pymeshlab()
    assert hasattr(pymeshlab.MeshSet(), "meshing_close_holes")


def test_missing_opengl_filters_give_the_install_sentence(monkeypatch):
    fake = types.ModuleType("pymeshlab")
    fake.MeshSet = type("MeshSet", (), {})
    monkeypatch.setitem(sys.modules, "pymeshlab", fake)
    with pytest.raises(TranslucencyError, match=r"apt-get install libgl1 libopengl0"):
        import_pymeshlab.__wrapped__()


def test_missing_pymeshlab(monkeypatch):
    monkeypatch.setitem(sys.modules, "pymeshlab", None)  # makes the import fail
    with pytest.raises(TranslucencyError, match="pymeshlab is not installed"):
        import_pymeshlab.__wrapped__()
