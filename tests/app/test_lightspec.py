"""Light specifications (``--light``): every kind, several at once, and the ones refused."""

import numpy as np
import pytest

from translucency.app.lightspec import parse_light_spec
from translucency.errors import InvalidParameterError
from translucency.scatter.lights import DirectionalLight, EnvironmentLight, PointLight


def test_parse_light_spec():
    (default,) = parse_light_spec("0,0,2")
    assert isinstance(default, DirectionalLight) and np.allclose(default.irradiance_rgb, 1.0)
    lights = parse_light_spec("dir:1,0,0:3; point:0,0,200:0.5,0.5,1 ; env:0.2:64")
    assert [type(light) for light in lights] == [DirectionalLight, PointLight, EnvironmentLight]
    assert np.allclose(lights[0].irradiance_rgb, 3.0)
    assert np.allclose(lights[1].intensity_rgb, (0.5, 0.5, 1.0))
    assert lights[2].n_directions == 64
    for bad in ("", "lamp:1,2,3", "dir:a,b,c", "env:1:many", "dir:0,0,0"):
        with pytest.raises(InvalidParameterError):
            parse_light_spec(bad)
