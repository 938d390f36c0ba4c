"""Shared fixtures: the spec folder and the shared scans, both beside the repository (skipped when absent)."""

import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
SPEC = SHARED / "spec"
MESHES = SHARED / "meshes"


@pytest.fixture(scope="session")
def dirpole_vectors():
    """The independent reference vectors of the directional dipole (shared/spec/dirpole_vectors.json)."""
    path = SPEC / "dirpole_vectors.json"
    if not path.exists():
        pytest.skip(f"reference vectors not found: {path.name} (expected in ../shared/spec)")
    return json.loads(path.read_text())


@pytest.fixture(scope="session")
def shared_meshes():
    """Folder of the shared real scans; skips the test when it is absent."""
    if not MESHES.is_dir():
        pytest.skip("the shared scans (../shared/meshes) are not present")
    return MESHES
