"""The display transform and the luminance, against the published standards' numbers."""

import numpy as np

from translucency.app.display import display_colors, luminance, srgb_encode


def test_srgb_encode_matches_iec_61966_2_1():
    # the standard's piecewise curve at its break point and at 0.5 (0.735356...), and its clipping
    assert srgb_encode(0.0031308) == np.float64(12.92 * 0.0031308)
    assert abs(srgb_encode(0.5) - 0.7353569830524495) < 1e-12
    assert abs(srgb_encode(2.0) - 1.0) < 1e-15 and srgb_encode(-1.0) == 0.0


def test_luminance_is_the_y_row_of_the_srgb_to_xyz_matrix():
    # IEC 61966-2-1 / Rec. 709 linear RGB -> XYZ, row Y: 0.2126 0.7152 0.0722 (white has Y = 1)
    rgb = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.2, 0.4, 0.8]])
    expected = np.array([0.2126, 0.7152, 0.0722, 1.0, 0.2 * 0.2126 + 0.4 * 0.7152 + 0.8 * 0.0722])
    assert np.allclose(luminance(rgb), expected, rtol=0, atol=1e-4)
    assert luminance(rgb.reshape(1, 5, 3)).shape == (1, 5)


def test_display_colors_maps_the_995th_percentile_to_0_9():
    radiance = np.linspace(0.0, 2.0, 3000)[:, None] * np.ones(3)
    colors, exposure = display_colors(radiance)
    level = np.percentile(radiance.max(axis=1), 99.5)
    assert abs(exposure * level - 0.9) < 1e-12
    # the brightest vertex: 2.0 * exposure = 0.9045 linear -> sRGB 0.9568 -> 243.98 (rounds to 244)
    assert colors.dtype == np.uint8 and colors.max() == 244 and colors.min() == 0
