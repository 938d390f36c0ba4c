"""bench/aggregation.py: the error of aggregating light samples per vertex, against per-direction summation."""

import numpy as np
import pytest
from aggregation import aggregation_error

from tests.scatter.test_irradiance import ETA, icosphere
from translucency.errors import InvalidParameterError
from translucency.scatter.irradiance import incident_flux
from translucency.scatter.lights import DirectionalLight
from translucency.scatter.medium import Medium


def test_aggregation_error_is_zero_for_one_light_and_measured_for_several():
    points, _, normals, areas = icosphere(radius=5.0, subdivisions=2)
    medium = Medium([0.0021, 0.0041, 0.0071], [2.19, 2.62, 3.00], 0.0, 1.5)  # marble-like, 1/mm
    receivers = [0, 5, 17, 40]
    one = incident_flux(points, normals, areas, DirectionalLight((0, 0, 1)), ETA, per_direction=True)
    assert aggregation_error(points, normals, one, medium, receivers)["max_relative_error"] < 1e-12
    two = incident_flux(
        points, normals, areas, [DirectionalLight((0, 0, 1)), DirectionalLight((1, 0, 0))], ETA, per_direction=True
    )
    report = aggregation_error(points, normals, two, medium, receivers)
    assert np.all(np.isfinite(report["B_aggregated"])) and np.all(report["B_per_direction"] >= 0)
    assert 0 < report["max_relative_error"] < 1
    with pytest.raises(InvalidParameterError, match="per_direction=True"):
        aggregation_error(
            points, normals, incident_flux(points, normals, areas, DirectionalLight((0, 0, 1)), ETA), medium, receivers
        )
