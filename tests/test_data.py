"""The reference values carried in tests/data are the published ones, unchanged."""

import hashlib
from pathlib import Path

import pytest

from .conftest import DATA, SHARED

#: SHA-256 of each published reference file, taken from the independent reference folder.
PUBLISHED_SHA256 = {
    "dirpole_vectors.json": "a386837f9df7c2b409b8c2a8d773aba89de8dbd3e7d6a4c5f47be25619d0cc27",
}


@pytest.mark.parametrize("name", sorted(PUBLISHED_SHA256))
def test_carried_reference_values_match_their_source(name):
    """The carried copy has the published file's checksum (a clone alone checks this), and when the
    independent reference folder is beside the clone it equals that file byte for byte."""
    carried = (DATA / name).read_bytes()
    assert hashlib.sha256(carried).hexdigest() == PUBLISHED_SHA256[name]
    source = Path(SHARED) / "spec" / name
    if source.exists():
        assert carried == source.read_bytes()
