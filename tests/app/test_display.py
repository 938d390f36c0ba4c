"""The display transform and the luminance, against the published standards' numbers."""

import numpy as np
import pytest

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


def test_false_colour_values_are_luminance_or_one_channel_in_the_radiance_unit():
    from translucency.app.display import false_colour_values

    rgb = np.array([[1.0, 1.0, 1.0], [0.2, 0.4, 0.8]])
    # white has Y = 1 (Rec. 709 / sRGB primaries, D65), whatever the unit: Y is in the unit of L
    assert np.allclose(false_colour_values(rgb), [1.0, 0.2 * 0.2126 + 0.4 * 0.7152 + 0.8 * 0.0722], atol=1e-4)
    assert np.array_equal(false_colour_values(rgb, "green"), rgb[:, 1])
    assert np.array_equal(false_colour_values(rgb, "blue"), rgb[:, 2])


def test_false_colour_range_tops_at_what_srgb_shows_as_white():
    from translucency.app.display import LOG_DECADES, false_colour_label, false_colour_range

    assert false_colour_range(np.ones(3), "linear", exposure=4.0) == (0.0, 0.25)  # srgb(4 * 0.25) = 1
    low, high = false_colour_range(np.ones(3), "log", exposure=4.0)
    assert high == 0.25 and np.isclose(high / low, 10**LOG_DECADES)
    # no exposure: the automatic exposure's rule, the 99.5th percentile shown at 0.9
    values = np.linspace(0.0, 2.0, 3000)
    assert np.isclose(false_colour_range(values, "linear")[1], np.percentile(values, 99.5) / 0.9)
    assert "W/(m² sr) per W/m²" in false_colour_label("luminance", "log")


@pytest.mark.parametrize("call", ["values", "range"])
def test_false_colour_choices_are_checked(call):
    from translucency.app.display import false_colour_range, false_colour_values
    from translucency.errors import InvalidParameterError

    with pytest.raises(InvalidParameterError, match="one of"):
        false_colour_values(np.ones((2, 3)), "hue") if call == "values" else false_colour_range(np.ones(2), "sqrt")
