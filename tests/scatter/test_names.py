"""The solver's choices by name: each check accepts exactly the choices and says what to change."""

import numpy as np
import pytest

from translucency.errors import InvalidParameterError, command_line_spelling
from translucency.scatter.names import DEVICES, METHODS, MODELS, check_device, check_method, check_model, check_tol


def test_every_choice_passes_unchanged():
    assert [check_model(m) for m in MODELS] == list(MODELS)
    assert [check_method(m) for m in METHODS] == list(METHODS)
    assert [check_device(d) for d in DEVICES] == list(DEVICES)
    for tol in (1e-9, 0.01, np.float32(0.5), 0.999):
        assert check_tol(tol) is tol


@pytest.mark.parametrize(
    "check, value, words",
    [
        (check_model, "photon", "unknown model 'photon'; choose one of directional, standard, better."),
        (check_method, "fmm", "unknown method 'fmm'; choose one of exact, cutoff, tree, relight, auto."),
        (check_device, "tpu", "device must be one of cpu, gpu, auto, got 'tpu'."),
        (check_tol, 0.0, "tol must be a relative error in (0, 1), got 0.0."),
        (check_tol, 1.0, "tol must be a relative error in (0, 1), got 1.0."),
        (check_tol, float("nan"), "tol must be a relative error in (0, 1), got nan."),
        (check_tol, True, "tol must be a relative error in (0, 1), got True."),
        (check_tol, "0.01", "tol must be a relative error in (0, 1), got '0.01'."),
    ],
)
def test_a_wrong_choice_is_one_sentence(check, value, words):
    with pytest.raises(InvalidParameterError) as info:
        check(value)
    assert str(info.value) == words


def test_the_tolerance_is_named_as_the_user_wrote_it():
    with command_line_spelling(), pytest.raises(InvalidParameterError, match=r"^--tol must be"):
        check_tol(2.0)
