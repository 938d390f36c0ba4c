"""A material given four ways -- catalogue name, material file, coefficients on the command line, appearance
on the command line -- gives the same medium and the same B; every mistake is one sentence."""

import json

import numpy as np
import pytest

from translucency.app import cli
from translucency.app.options import solver_settings
from translucency.app.shading.scene import Scene
from translucency.app.shading.settings import ShadeSettings
from translucency.errors import InvalidParameterError, UnknownMaterialError
from translucency.geometry.mesh import TriangleMesh
from translucency.geometry.synthetic import icosphere
from translucency.scatter.appearance import appearance_of
from translucency.scatter.materials import material


def _args(argv):
    """The parsed options of ``bake`` for ``argv`` (a mesh name that is never read)."""
    return cli.build_parser().parse_args(["bake", "scan.ply", *argv])


def _csv(values):
    return ",".join(repr(float(v)) for v in values)


def _four_ways(tmp_path):
    """marble by name, by a TOML file of its coefficients, by --sigma-a/--sigma-s/--g/--eta and by
    --reflectance/--mfp/--eta (its appearance)."""
    marble = material("marble").medium()
    toml = tmp_path / "stone.toml"
    toml.write_text(
        f"sigma_a = [{_csv(marble.sigma_a)}]\nsigma_s = [{_csv(marble.sigma_s)}]\ng = {float(marble.g[0])!r}\n"
        f"eta = {marble.eta!r}\n"
    )
    reflectance, path = appearance_of(marble)
    return marble, [
        ["--material", "marble"],
        ["--material", str(toml)],
        ["--sigma-a", _csv(marble.sigma_a), "--sigma-s", _csv(marble.sigma_s), "--g", "0", "--eta", repr(marble.eta)],
        ["--reflectance", _csv(reflectance), "--mfp", _csv(path), "--eta", repr(marble.eta)],
    ]


def test_four_ways_to_give_a_material_give_the_same_coefficients_and_B(tmp_path):
    marble, ways = _four_ways(tmp_path)
    assert float(marble.g[0]) == 0.0  # the inline line passes g = 0
    points, triangles = icosphere(2, 20.0)
    scene = Scene(TriangleMesh(points, triangles), shadows=False)
    results = []
    for argv in ways:
        medium = solver_settings(_args(argv)).material
        np.testing.assert_allclose(medium.sigma_a, marble.sigma_a, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(medium.sigma_s, marble.sigma_s, rtol=1e-9)
        assert medium.eta == marble.eta
        results.append(scene.shade_with(ShadeSettings(material=medium, bounces=0, time_limit=None)).B)
    for B in results[1:]:
        np.testing.assert_allclose(B, results[0], rtol=1e-7, atol=1e-12 * results[0].max())


def test_a_json_file_and_a_python_mapping_are_the_same_definition(tmp_path):
    definition = {"name": "jade", "reflectance": [0.55, 0.8, 0.5], "mfp": [1.5, 2.0, 1.2], "eta": 1.6, "scale": 2}
    (tmp_path / "jade.json").write_text(json.dumps(definition))
    from_file = ShadeSettings(material=str(tmp_path / "jade.json")).material
    from_mapping = ShadeSettings(material=definition).material
    assert from_file.name == from_mapping.name == "jade"
    np.testing.assert_array_equal(from_file.sigma_a, from_mapping.sigma_a)
    _, path = appearance_of(from_file)
    np.testing.assert_allclose(path, np.array([1.5, 2.0, 1.2]) / 2)  # scale 2: coefficients doubled
    assert ShadeSettings(material=str(tmp_path / "jade.json")).metadata([], "full")["material"] == "jade"


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--sigma-a", "0.1,0.2,0.3"], "--sigma-a and --sigma-s go together: add --sigma-s"),
        (["--eta", "1.4"], "need the material they change"),
        (["--reflectance", "0.5", "--mfp", "1", "--sigma-a", "1", "--sigma-s", "1"], "not both kinds"),
        (["--reflectance", "0.5,0.6", "--mfp", "1"], "--reflectance must be one number or three numbers"),
        (["--reflectance", "1.5", "--mfp", "1"], "not between 0 and 1"),
        (["--reflectance", "0.5", "--mfp", "-1"], "mean free path"),
        (["--sigma-a", "-1", "--sigma-s", "1"], "sigma_a"),
    ],
)
def test_inline_mistakes_are_one_sentence(argv, words):
    with pytest.raises(InvalidParameterError, match=words.replace("(", r"\(")) as info:
        solver_settings(_args(argv))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "name, text, words",
    [
        ("a.toml", "sigma_a = [1, 2, 3\n", "not valid TOML"),
        ("a.json", "[1, 2]", "one table"),
        ("a.toml", "sigma_a = 0.1\n", "add sigma_s"),
        ("a.toml", "colour = 'red'\n", "unknown key"),
        ("a.toml", "material = 'marble'\nscale = 0\n", "scale must be a positive number"),
        ("a.toml", "reflectance = 1.0\nmfp = 1.0\n", "material file .*a.toml: reflectance 1"),
    ],
)
def test_material_file_mistakes_name_the_file(tmp_path, name, text, words):
    (tmp_path / name).write_text(text)
    with pytest.raises(InvalidParameterError, match=words) as info:
        ShadeSettings(material=str(tmp_path / name))
    assert name in str(info.value)


def test_a_missing_material_file_says_so(tmp_path):
    with pytest.raises(InvalidParameterError, match="does not exist"):
        ShadeSettings(material=str(tmp_path / "nowhere.toml"))


def test_compare_refuses_inline_numbers_in_a_sentence(capsys):
    assert cli.main(["compare", "--reflectance", "0.5", "--mfp", "1", "-o", "unused"]) == 2
    assert "write the material" in capsys.readouterr().err


def test_compare_takes_material_files_beside_names(tmp_path):
    from translucency.app.compare import validate_choices

    (tmp_path / "jade.toml").write_text("reflectance = [0.55, 0.8, 0.5]\nmfp = [1.5, 2.0, 1.2]\neta = 1.6\n")
    materials, _, media = validate_choices(f"marble,{tmp_path / 'jade.toml'}", "directional")
    assert materials == ["marble", "jade"]  # a file by its material's name, not its path
    assert media[materials[0]].name == "marble" and media[materials[1]].name == "jade"
    np.testing.assert_allclose(appearance_of(media[materials[1]])[0], [0.55, 0.8, 0.5], rtol=1e-9)


def test_a_sweep_over_the_mean_free_path_keeps_the_reflectance():
    from translucency.app.compare import validate_choices

    labels, _, media = validate_choices("marble", "directional", {"mfp": [0.5, 1, 2, 4]})
    assert labels == ["marble mfp=0.5", "marble mfp=1", "marble mfp=2", "marble mfp=4"]
    base, _ = appearance_of(material("marble").medium())
    for label, path in zip(labels, (0.5, 1, 2, 4)):
        reflectance, mfp = appearance_of(media[label])
        np.testing.assert_allclose(reflectance, base, rtol=1e-9)
        np.testing.assert_allclose(mfp, path, rtol=1e-12)
    _, _, scaled = validate_choices(["marble"], "directional", {"scale": [2]})
    np.testing.assert_allclose(scaled["marble scale=2"].sigma_a, 2 * material("marble").medium().sigma_a)


@pytest.mark.parametrize(
    "materials, sweep, words",
    [
        ("marble,ketchup", {"mfp": [1]}, "varies one material"),
        ("marble", {"mfp": [1], "eta": [1.4]}, "one key"),
        ("marble", {"colour": [1]}, "varies one of"),
        ("marble", {"mfp": []}, "at least one value"),
        ("marble", {"reflectance": [1.5]}, "not between 0 and 1"),
    ],
)
def test_sweep_mistakes_are_one_sentence(materials, sweep, words):
    from translucency.app.compare import validate_choices

    with pytest.raises(InvalidParameterError, match=words):
        validate_choices(materials, "directional", sweep)


def test_the_sweep_option_is_read_or_refused_in_a_sentence(capsys):
    assert cli._sweep("mfp=0.5,1,2") == {"mfp": [0.5, 1.0, 2.0]}
    assert cli.main(["compare", "--sweep", "mfp", "-o", "unused"]) == 2
    assert "--sweep must be KEY=V1,V2" in capsys.readouterr().err


def test_materials_show_prints_the_derived_quantities_and_the_look(tmp_path, capsys):
    assert cli.main(["materials", "--show", "marble"]) == 0
    out = capsys.readouterr().out
    reflectance, path = appearance_of(material("marble").medium())
    rows = {line.split()[0]: line for line in out.splitlines()[3:]}
    assert {"sigma_a", "sigma_s'", "alpha'", "D", "sigma_tr", "1/sigma_t'", "1/sigma_tr", "d_e", "R_d"} <= set(rows)
    assert f"{reflectance[0]:.4g}" in rows["R_d"] and f"{path[2]:.4g}" in rows["1/sigma_t'"]
    (tmp_path / "jade.toml").write_text("reflectance = [0.55, 0.8, 0.5]\nmfp = [1.5, 2.0, 1.2]\neta = 1.6\n")
    assert cli.main(["materials", "--show", str(tmp_path / "jade.toml")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("jade: eta 1.6") and "0.55, 0.8, 0.5" in out


def test_own_materials_are_found_by_name_after_the_catalogue_and_listed(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("TRANSLUCENCY_MATERIALS", str(tmp_path))
    (tmp_path / "Green Jade.toml").write_text("reflectance = [0.55, 0.8, 0.5]\nmfp = [1.5, 2.0, 1.2]\neta = 1.6\n")
    (tmp_path / "marble.json").write_text('{"material": "ketchup"}')  # the catalogue's marble comes first
    assert ShadeSettings(material="green_jade").material.name == "Green Jade"
    assert ShadeSettings(material="marble").material.sigma_a.tolist() == material("marble").medium().sigma_a.tolist()
    with pytest.raises(UnknownMaterialError, match=f"go in {tmp_path} as NAME.toml"):
        ShadeSettings(material="red_jade")
    assert cli.main(["materials"]) == 0
    assert "Green Jade" in capsys.readouterr().out


def test_without_the_folder_the_listing_says_where_own_materials_go(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("TRANSLUCENCY_MATERIALS", str(tmp_path / "none"))
    assert cli.main(["materials"]) == 0
    assert "your own materials: none; put NAME.toml" in capsys.readouterr().out


def test_the_metadata_holds_a_definition_that_gives_the_material_back(tmp_path):
    """What a bake records is enough to write the material down again (coefficients) and says its look."""
    settings = ShadeSettings(
        material={"name": "jade", "reflectance": [0.55, 0.8, 0.5], "mfp": [1.5, 2.0, 1.2], "eta": 1.6}
    )
    recorded = json.loads(json.dumps(settings.metadata([], "full")))["coefficients"]
    again = ShadeSettings(
        material={k: recorded[f"{k}_per_mm"] for k in ("sigma_a", "sigma_s")}
        | {"g": recorded["g"], "eta": recorded["eta"]}
    ).material
    np.testing.assert_allclose(again.sigma_a, settings.material.sigma_a, rtol=1e-15)
    np.testing.assert_allclose(recorded["diffuse_reflectance"], [0.55, 0.8, 0.5], rtol=1e-9)


def test_inline_materials_are_named_by_their_numbers():
    """Two inline definitions get two names (their bakes into one folder do not overwrite each other); the
    same numbers get the same name."""
    from translucency.app.options import inline_material

    first = inline_material(_args(["--reflectance", "0.5", "--mfp", "1"]))
    again = inline_material(_args(["--reflectance", "0.5", "--mfp", "1"]))
    other = inline_material(_args(["--reflectance", "0.5", "--mfp", "2"]))
    assert first.name == again.name != other.name
    assert first.name.startswith("custom-")
