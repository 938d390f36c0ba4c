"""bench/reference_mitsuba.py: the sensor faces it picks and a tiny run of its fast configuration."""

import math

import numpy as np
import pytest
from reference_mitsuba import CONFIGS, run_config, sensor_faces

from translucency.geometry.measure import triangle_normals
from translucency.geometry.synthetic import icosphere


def test_sensor_faces_are_distinct_and_near_their_targets():
    points, triangles = icosphere(3, 5.0)
    normals = triangle_normals(points, triangles)
    faces = sensor_faces(normals, 20, (10.0, 120.0))
    assert len(set(faces.tolist())) == 20
    polar = np.degrees(np.arccos(normals[faces, 2]))
    # a level-3 face spans about 4 deg, so each pick lies within a few degrees of its target's polar angle
    assert np.all(np.abs(polar - np.linspace(10.0, 120.0, 20)) < 6.0)


def test_the_fast_configuration_runs_and_records_what_reproduces_it():
    pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (the reference extra)")
    out = run_config("fast", CONFIGS["fast"], spp_scale=1 / 256, seed=1)
    (run,) = out["runs"]
    assert run["spp"] == 4096 and run["variant"] == "scalar_rgb" and run["mitsuba_version"]
    assert out["mesh"]["faces"] == 1280 and out["medium"]["eta"] == 1.3
    lit = np.asarray(out["sensors"]["lit"])
    assert lit.sum() >= 4 and np.all(np.asarray(run["radiance"])[lit] > 0)
    assert math.isfinite(run["relative_stderr_lit_median"])
