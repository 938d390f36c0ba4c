"""Shared command-line options: what the user types becomes lights and solver settings, or one sentence."""

import argparse

import numpy as np
import pytest

from translucency.app import options
from translucency.errors import InvalidParameterError, TranslucencyError
from translucency.scatter.lights import DirectionalLight, EnvironmentLight, PointLight


def parse(*argv):
    parser = argparse.ArgumentParser()
    options.add_scan_options(parser)
    options.add_light_options(parser)
    options.add_solver_options(parser)
    return parser.parse_args(list(argv))


def test_defaults_leave_the_light_to_the_pipeline_and_give_the_auto_method():
    args = parse()
    assert options.lights_from_args(args) is None  # the pipeline places it by the up axis
    assert args.unit is None and args.up == "auto"
    settings = options.solver_settings(args)
    assert settings.method == "auto" and settings.tol == 0.01 and settings.resolution == "auto"
    assert settings.material.name == "marble" and args.mesh is None


def test_light_options_add_up():
    args = parse("--light-dir", "0,0,2", "--light", "point:0,0,100:3;env:0.1:16")
    lights = options.lights_from_args(args)
    assert [type(light) for light in lights] == [DirectionalLight, PointLight, EnvironmentLight]
    np.testing.assert_allclose(lights[0].direction, (0, 0, 1))  # normalised, toward the light
    assert lights[2].n_directions == 16


@pytest.mark.parametrize("text", ["1,2", "a,b,c", "0,0,0", "1,nan,0", ""])
def test_bad_light_direction_is_one_sentence(text):
    with pytest.raises(InvalidParameterError, match="--light-dir"):
        options.lights_from_args(parse("--light-dir", text))


@pytest.mark.parametrize(
    "flag, value, words",
    [
        ("--tol", "2", "--tol"),
        ("--resolution", "fine", "--resolution"),
        ("--exposure", "-1", "--exposure"),
        ("--material", "plutonium", "plutonium"),
        ("--device", "gpu", "--device gpu needs an NVIDIA GPU, and .*; choose --device cpu or --device auto"),
    ],
)
def test_bad_solver_settings_are_one_sentence(flag, value, words):
    with pytest.raises(TranslucencyError, match=words):
        options.solver_settings(parse(flag, value))


def test_the_parser_offers_exactly_the_solvers_choices():
    from translucency.scatter import kernels, solve

    assert options.MODELS == solve.MODELS == tuple(kernels.MODELS) and options.METHODS == solve.METHODS


def test_the_device_is_a_setting_and_the_parser_offers_its_choices():
    from translucency.scatter.names import DEVICES

    assert options.DEVICES == DEVICES
    assert options.solver_settings(parse("--device", "cpu")).device == "cpu"
    assert options.solver_settings(parse()).device == "auto"


@pytest.mark.parametrize("value, axis", [("-z", "-z"), ("x", "x"), ("auto", "auto")])
def test_up_takes_negative_axes_as_written(value, axis):
    from translucency.app import cli

    args = cli.build_parser().parse_args(["view", "--up", value])
    assert args.up == axis


def test_light_dir_help_says_the_scan_frame():
    parser = argparse.ArgumentParser()
    options.add_light_options(parser)
    assert "scan's own frame" in parser.format_help().replace("\n", " ").replace("  ", " ")
