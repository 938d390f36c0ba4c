"""Shared fixtures: the reference values (carried in tests/data) and the shared scans beside the repository.

The reference values are numbers computed independently of this code; they travel with the tests so a
clone alone runs every golden-value test. Only the tests on the real scans skip when the scans are absent.
"""

import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
DATA = Path(__file__).resolve().parent / "data"
MESHES = SHARED / "meshes"


@pytest.fixture(scope="session")
def dirpole_vectors():
    """The independent reference vectors of the directional dipole (tests/data/dirpole_vectors.json)."""
    return json.loads((DATA / "dirpole_vectors.json").read_text())


@pytest.fixture(scope="session")
def shared_meshes():
    """Folder of the shared real scans; skips the test when it is absent."""
    if not MESHES.is_dir():
        pytest.skip("the shared scans (../shared/meshes) are not present")
    return MESHES


@pytest.fixture
def fifo(tmp_path):
    """A function that makes a FIFO (named pipe) in the test's folder and returns its path; skips where the
    system has none. Opening one for reading waits for a writer: what every reader must refuse before opening."""
    import os

    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs on this system")

    def make(name):
        path = tmp_path / name
        os.mkfifo(path)
        return path

    return make
