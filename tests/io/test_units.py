"""Length units and the plausibility of a scan's size."""

import warnings

import pytest

from translucency.errors import InvalidParameterError, MeshError, command_line_spelling
from translucency.io.units import (
    PLAUSIBLE_EXTENT,
    UNITS,
    ImplausibleSizeWarning,
    UnitInferredWarning,
    check_extent,
    infer_unit,
    inferred_unit_message,
    likely_unit,
    parse_unit,
    unit_label,
    unit_metadata,
)


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


# --- inference when no unit is given -------------------------------------------------------------


@pytest.mark.parametrize(
    "extent, unit",
    [
        (0.005, "m"),
        (0.0051, "m"),
        (0.1557, "m"),
        (1.0, "m"),
        (4.99, "m"),
        (5.0, "mm"),
        (5.01, "mm"),
        (321.8, "mm"),
        (4999.0, "mm"),
        (5000.0, "mm"),
    ],
)
def test_infer_unit_around_the_thresholds(extent, unit):
    assert infer_unit(extent) == unit
    assert PLAUSIBLE_EXTENT[0] <= extent * UNITS[unit] <= PLAUSIBLE_EXTENT[1]


@pytest.mark.parametrize("extent", [0.0049, 1e-4, 5001.0, 2e5])
def test_a_size_no_unit_makes_plausible_is_refused_with_a_sentence(extent):
    with pytest.raises(MeshError) as info:
        infer_unit(extent, "odd.ply")
    message = str(info.value)
    assert message.startswith("odd.ply is ") and "no unit makes that a plausible scan" in message
    assert "pass unit= with the file's unit" in message and message.count(". ") == 0 and message.endswith(".")
    with command_line_spelling(), pytest.raises(MeshError, match="no --unit was given.*pass --unit with"):
        infer_unit(extent, "odd.ply")


@pytest.mark.parametrize(
    "extent, words", [(1e15, "larger than any"), (1e-12, "smaller than any"), (0.0, "one position")]
)
def test_absurd_sizes_keep_their_own_sentence_when_inferring(extent, words):
    with pytest.raises(MeshError, match=words):
        infer_unit(extent, "x.ply")


def test_inferred_unit_line_names_the_unit_in_words_and_the_setting():
    assert inferred_unit_message("stanford_bunny_zipper.ply", 0.1557, "m") == (
        "stanford_bunny_zipper.ply: no unit= given; 0.156 units across, read as metres (156 mm); pass unit= to override"
    )
    with command_line_spelling():
        assert inferred_unit_message("angel.ply", 321.76, "mm") == (
            "angel.ply: no --unit given; 322 units across, read as millimetres (322 mm); pass --unit to override"
        )


def test_implausible_warning_spells_the_flag_on_the_command_line():
    with command_line_spelling(), pytest.warns(ImplausibleSizeWarning) as caught:
        check_extent(0.1557, 1.0, "bunny.ply")
    assert "pass --unit m." in str(caught[0].message) and "unit='m'" not in str(caught[0].message)


def test_unit_metadata_records_name_factor_and_whether_inferred():
    # the coordinates are in mm whatever the file's unit: the file's unit is named source_...
    assert unit_metadata(1000.0, True) == {
        "length_unit": "mm",
        "source_unit": "m",
        "source_unit_name": "metres",
        "source_mm_per_unit": 1000.0,
        "source_unit_inferred": True,
    }
    assert unit_metadata(2.5)["source_unit_name"] == "units of 2.5 mm"
    assert unit_metadata(2.5)["source_unit_inferred"] is False


# the shared scans state no unit; inferred, each comes out at its real size (largest extent, mm)
SHARED_SIZES = [
    ("stanford_bunny_zipper.ply", "m", "metres", 155.7),
    ("cyberware_horse.ply", "m", "metres", 183.3),
    ("cyberware_igea.ply", "m", "metres", 99.3),
    ("cyberware_igea_tristrips.ply", "m", "metres", 99.3),
    ("ggg_angel_sfm.ply", "mm", "millimetres", 321.8),
    ("ggg_angel_sfm.vtp", "mm", "millimetres", 321.8),
    ("ggg_birdbath_sfm.ply", "mm", "millimetres", 308.2),
    ("ggg_birdbath_sfm.vtp", "mm", "millimetres", 308.2),
]


@pytest.mark.parametrize("name, unit, words, extent_mm", SHARED_SIZES, ids=[s[0] for s in SHARED_SIZES])
def test_shared_scans_are_inferred_at_their_real_size(name, unit, words, extent_mm):
    from translucency.io import load_mesh

    from .conftest import shared_scan

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = load_mesh(shared_scan(name))
    assert mesh.extent == pytest.approx(extent_mm, abs=0.05)
    assert mesh.mm_per_unit == UNITS[unit] and mesh.unit_inferred
    lines = [str(w.message) for w in caught]
    assert [w.category for w in caught] == [UnitInferredWarning]  # one line, and no implausible-size warning
    assert lines[0].startswith(f"{name}: no unit= given; ") and f"read as {words} ({extent_mm:.3g} mm)" in lines[0]


def test_a_given_unit_is_not_inferred_and_says_nothing():
    from translucency.io import load_mesh

    from .conftest import shared_scan

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = load_mesh(shared_scan("stanford_bunny_zipper.ply"), unit="m")
    assert mesh.unit_inferred is False and mesh.mm_per_unit == 1000.0


def test_embedded_default_keeps_its_size_and_is_not_inferred():
    from translucency.app.shading.scan import DEFAULT_SCAN_WIDTH_MM, load_default_scan

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = load_default_scan()
    assert mesh.extent == pytest.approx(DEFAULT_SCAN_WIDTH_MM) and not mesh.unit_inferred


def test_inferred_unit_survives_cleaning_and_decimation(tmp_path):
    from translucency.io import clean_mesh, decimate_mesh, load_mesh

    from .conftest import icosphere
    from .test_load import write_ply

    points, triangles = icosphere(3, 0.08)  # 0.16 units across: metres
    path = write_ply(tmp_path / "ball.ply", points, triangles)
    with pytest.warns(UnitInferredWarning, match="read as metres"):
        mesh = load_mesh(path)
    cleaned, _ = clean_mesh(mesh)
    proxy = decimate_mesh(cleaned, target_faces=200).proxy
    assert cleaned.unit_inferred and proxy.unit_inferred and proxy.mm_per_unit == 1000.0
