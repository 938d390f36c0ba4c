"""Materials from their look: the inversion of the better dipole's total reflectance (docs/physics.md §6.4)."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError
from translucency.scatter import dipoles
from translucency.scatter.appearance import appearance_of, medium_from_appearance, reduced_albedo
from translucency.scatter.materials import material, material_names

from .test_dipoles import SPEC_TOTALS_13


@pytest.mark.parametrize("alpha, directional, standard, better", SPEC_TOTALS_13)
def test_inverting_the_spec_table_gives_its_albedo(alpha, directional, standard, better):
    """The spec's better-dipole totals (4 decimals; within 1e-4 of the closed form, as test_dipoles allows)
    invert to the spec's albedos within 1e-4 over the total's slope there."""
    slope = (
        dipoles.better_dipole_total_reflectance(alpha + 1e-4, 1.3)
        - dipoles.better_dipole_total_reflectance(alpha - 1e-4, 1.3)
    ) / 2e-4
    found = reduced_albedo(better, 1.3)[0]
    assert found == pytest.approx(alpha, abs=1e-4 / slope)
    assert dipoles.better_dipole_total_reflectance(found, 1.3) == pytest.approx(better, abs=1e-14)


@pytest.mark.parametrize("eta", [1.0, 1.3, 1.5, 2.0])
def test_the_total_rises_monotonically_so_each_reflectance_has_one_albedo(eta):
    alpha = np.linspace(0.0, 1.0, 20001)
    total = dipoles.better_dipole_total_reflectance(alpha, eta)
    assert total[0] == 0.0 and total[-1] == pytest.approx(1.0, abs=1e-12)
    assert np.all(np.diff(total) > 0)


def _absorbing_and_scattering(name):
    """Catalogue entries the diffusion models take (they scatter in every channel) that absorb in every
    channel (without absorption the reflectance is 1, which no finite albedo has)."""
    entry = material(name)
    return bool(np.all(np.array(entry.sigma_s) > 0) and np.all(np.array(entry.sigma_a) > 0))


@pytest.mark.parametrize("name", [n for n in material_names() if _absorbing_and_scattering(n)])
def test_round_trip_of_every_catalogue_material(name):
    """coefficients -> (reflectance, mean free path) -> coefficients, within 1e-6 (the issue's bound)."""
    medium = material(name).medium()
    reflectance, path = appearance_of(medium)
    again = medium_from_appearance(reflectance, path, medium.eta, medium.g)
    np.testing.assert_allclose(again.sigma_a, medium.sigma_a, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(again.sigma_s, medium.sigma_s, rtol=1e-6)
    np.testing.assert_allclose(again.g, medium.g)
    assert again.eta == medium.eta


def test_appearance_first_then_back():
    """(reflectance, path) -> coefficients -> (reflectance, path), and the coefficients by hand."""
    medium = medium_from_appearance([0.8, 0.5, 0.2], [1.0, 2.0, 0.5], eta=1.4, g=0.5)
    reflectance, path = appearance_of(medium)
    np.testing.assert_allclose(reflectance, [0.8, 0.5, 0.2], rtol=1e-9)
    np.testing.assert_allclose(path, [1.0, 2.0, 0.5], rtol=1e-12)
    np.testing.assert_allclose(medium.sigma_a + medium.sigma_s * (1 - medium.g), 1.0 / np.array([1.0, 2.0, 0.5]))
    assert medium_from_appearance(0.5, 1.0).sigma_a.shape == (3,)  # scalars for every channel


def test_without_absorption_the_reflectance_is_one_which_is_refused():
    """A medium that does not absorb reflects everything that enters (spectralon's blue): the limit alpha' = 1."""
    reflectance, _ = appearance_of(material("spectralon").medium())
    assert reflectance.max() == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(InvalidParameterError, match="not between 0 and 1"):
        reduced_albedo(1.0)


@pytest.mark.parametrize("reflectance", [0.0, 1.0, 1.2, -0.1, float("nan")])
def test_a_reflectance_no_albedo_gives_is_refused_in_one_sentence(reflectance):
    with pytest.raises(InvalidParameterError, match="not between 0 and 1") as info:
        medium_from_appearance([0.5, reflectance, 0.5], 1.0)
    assert "(green)" in str(info.value) and str(info.value).count(". ") == 0


@pytest.mark.parametrize("path", [0.0, -1.0, float("inf")])
def test_a_mean_free_path_that_is_not_a_positive_length_is_refused(path):
    with pytest.raises(InvalidParameterError, match="mean free path"):
        medium_from_appearance(0.5, [1.0, 1.0, path])


def test_the_readme_example_makes_the_material_it_describes(monkeypatch):
    """The README's block under "## Materials" runs (the shade swapped for a stand-in that keeps its
    arguments) and gives a jade whose look is what was asked."""
    import re
    from pathlib import Path

    import translucency as tl

    text = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", text[text.index("## Materials") :], re.S).group(1)
    calls = []
    monkeypatch.setattr(tl, "shade", lambda *args, **kwargs: calls.append(args))
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    reflectance, path = appearance_of(namespace["jade"])
    np.testing.assert_allclose(reflectance, [0.55, 0.8, 0.5], rtol=1e-9)
    np.testing.assert_allclose(path, [1.5, 2.0, 1.2], rtol=1e-12)
    assert calls and calls[0][1] is namespace["jade"]
