"""Length units and the plausibility of a scan's size."""

import warnings

import pytest

from translucency.errors import InvalidParameterError, MeshError
from translucency.io.units import ImplausibleSizeWarning, check_extent, likely_unit, parse_unit, unit_label


@pytest.mark.parametrize(
    "unit, factor",
    [("mm", 1.0), ("cm", 10.0), ("m", 1000.0), ("in", 25.4), ("M", 1000.0), (2.5, 2.5), ("0.5", 0.5), (3, 3.0)],
)
def test_parse_unit(unit, factor):
    assert parse_unit(unit) == factor


@pytest.mark.parametrize("unit", ["km", "", "feet", -1, 0, float("nan"), float("inf"), None, True, "-2"])
def test_parse_unit_rejects(unit):
    with pytest.raises(InvalidParameterError, match="unit"):
        parse_unit(unit)


def test_unit_label():
    assert unit_label(1000.0) == "m"
    assert unit_label(25.4) == "in"
    assert unit_label(2.5) == "2.5 mm"


def test_bunny_in_mm_names_metres():
    # the shared bunny is 0.1557 units wide: as mm it is 0.16 mm, as metres a 156 mm figurine
    assert likely_unit(0.1557) == "m"
    with pytest.warns(ImplausibleSizeWarning, match=r"0\.16 mm across.*metres pass unit='m'"):
        check_extent(0.1557, 1.0, "bunny.ply")


def test_plausible_sizes_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_extent(155.7, 1000.0, "bunny.ply")
        check_extent(321.8, 1.0, "angel.ply")


def test_huge_mm_file_suggests_nothing_or_smaller_unit():
    with pytest.warns(ImplausibleSizeWarning, match="implausible"):
        check_extent(2.0e6, 1000.0, "big.ply")  # 2 km


@pytest.mark.parametrize("extent", [0.0, 1e-9, 1e12, float("inf"), float("nan")])
def test_absurd_sizes_are_errors(extent):
    with pytest.raises(MeshError, match="absurd|across|one position|larger|smaller"):
        check_extent(extent, 1.0, "x.ply")
