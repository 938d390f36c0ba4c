"""The material catalogue: lookups, provenance, published values and their computed reflectances."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, UnknownMaterialError
from translucency.scatter import dipoles, materials


def test_catalogue_holds_both_tables():
    entries = materials.catalogue()
    tables = {m.table for m in entries}
    assert tables == {"jensen2001", "narasimhan2006"}
    assert sum(m.table == "jensen2001" for m in entries) == 12
    assert sum(m.table == "narasimhan2006" for m in entries) == 34
    info = materials.material_tables()
    for table in info.values():
        assert table["units"] == "1/mm"
        assert table["source"]
    assert info["jensen2001"]["sigma_s_is_reduced"] is True
    assert info["narasimhan2006"]["sigma_s_is_reduced"] is False
    assert "DILUTED" in info["narasimhan2006"]["notes"].upper()


@pytest.mark.parametrize("spelling", ["skim_milk", "Skim milk", "SKIMMILK", " skim-milk "])
def test_lookup_ignores_case_space_and_punctuation(spelling):
    assert materials.material(spelling).key == "skim_milk"


def test_unknown_name_lists_close_matches():
    with pytest.raises(UnknownMaterialError) as info:
        materials.material("marbel")
    assert "marble" in str(info.value)
    with pytest.raises(UnknownMaterialError) as info:
        materials.material("grapefruit")
    assert "white_grapefruit_juice" in str(info.value) and "ruby_grapefruit_juice" in str(info.value)
    assert isinstance(info.value, KeyError)


def test_jensen_values_and_decisions():
    # Decisions of docs/physics.md §11.1: Chicken red sigma_a 0.015 / 0.018, marble eta 1.5;
    # Jensen gives reduced sigma_s, g = 0.
    assert materials.material("chicken1").sigma_a[0] == 0.015
    assert materials.material("chicken2").sigma_a[0] == 0.018
    marble = materials.material("marble")
    assert marble.eta == 1.5
    assert marble.sigma_s == (2.19, 2.62, 3.00) and marble.sigma_a == (0.0021, 0.0041, 0.0071)
    assert materials.material("ketchup").sigma_s == (0.18, 0.07, 0.03)
    assert all(
        m.g == (0.0, 0.0, 0.0) and (m.eta == 1.3 or m.key == "marble")
        for m in materials.catalogue()
        if m.table == "jensen2001"
    )


def test_narasimhan_values_are_the_published_diluted_ones():
    grapefruit = materials.material("white grapefruit juice")
    assert grapefruit.sigma_s == (0.3513, 0.3669, 0.5237)
    assert grapefruit.sigma_a == (0.0096, 0.0131, 0.0395)
    assert grapefruit.g == (0.548, 0.545, 0.565)
    assert grapefruit.eta == 1.33
    # SAMPLE writes sigma_t = (0.3609, 0.3800, 0.5632) for the same material (docs/physics.md §11.2)
    assert np.allclose(np.add(grapefruit.sigma_s, grapefruit.sigma_a), [0.3609, 0.3800, 0.5632], atol=1e-12)
    medium = materials.material("lowfat chocolate milk").medium()
    assert np.allclose(medium.g, [0.934, 0.927, 0.916])


# docs/physics.md §11.1, last column (§10.6): total diffuse reflectance computed with the standard
# dipole at eta = 1.3 (3 decimals).
SPEC_RD = {
    "apple": (0.846, 0.841, 0.528),
    "chicken1": (0.314, 0.156, 0.126),
    "chicken2": (0.321, 0.160, 0.108),
    "cream": (0.976, 0.900, 0.725),
    "ketchup": (0.164, 0.006, 0.002),
    "marble": (0.867, 0.834, 0.801),
    "potato": (0.764, 0.613, 0.213),
    "skim_milk": (0.815, 0.813, 0.682),
    "skin1": (0.436, 0.227, 0.131),
    "skin2": (0.623, 0.433, 0.343),
    "spectralon": (1.0, 1.0, 1.0),
    "whole_milk": (0.908, 0.881, 0.759),
}


@pytest.mark.parametrize("name, expected", SPEC_RD.items())
def test_computed_total_reflectance_of_jensen_materials(name, expected):
    medium = materials.material(name).medium()
    computed = dipoles.standard_dipole_total_reflectance(medium.alpha_reduced, 1.3)
    assert np.allclose(computed, expected, atol=5.1e-4)


def test_marble_at_its_own_index():
    medium = materials.material("marble").medium()
    assert np.allclose(
        dipoles.standard_dipole_total_reflectance(medium.alpha_reduced, medium.eta), (0.830, 0.791, 0.753), atol=5.1e-4
    )


def test_non_scattering_channels_are_refused_with_a_sentence():
    grape = materials.material("grape_juice")
    assert not grape.is_diffusive
    assert list(grape.scattering_channels) == [True, False, False]
    with pytest.raises(InvalidParameterError, match="does not scatter in the green, blue"):
        grape.medium()


def test_every_diffusive_entry_builds_a_medium():
    for entry in materials.catalogue():
        if entry.is_diffusive:
            medium = entry.medium()
            assert medium.name == entry.key
            assert np.all(medium.sigma_t_reduced > 0)
    assert sum(not m.is_diffusive for m in materials.catalogue()) == 5  # coke, pepsi, merlot, coors, grape juice


def test_medium_scale_converts_units():
    per_mm = materials.material("potato").medium()
    per_cm = materials.material("potato").medium(scale=10.0)
    assert np.allclose(per_cm.sigma_a, per_mm.sigma_a * 10)
