import colour
import numpy as np
import pytest

from workbench.colour_management import (
    engine_render,
    level2_texture,
    light_colour,
    target_dac,
)
from workbench.colorimetry import WORKING_SHAPE
from workbench.display import SRGBDisplay
from workbench.illuminants import get_illuminant
from workbench.samples import ces99


def test_level1_white_texel_renders_the_light_colour():
    light = light_colour(get_illuminant("cie-d50").sd)
    out = engine_render(np.array([[255, 255, 255]]), light.rgb8)
    assert out[0].tolist() == light.rgb8.tolist()


def test_level2_reproduces_the_target_dac_on_every_source():
    patches = ces99().reflectances
    for source in ("cie-d65", "cie-a", "d65-two-peak", "cie-fl11"):
        texture = level2_texture(patches, get_illuminant(source).sd)
        out = engine_render(texture.rgb8, texture.light.rgb8)
        reachable = ~texture.unreachable
        diff = np.abs(out[reachable] - np.round(texture.target_dac[reachable]))
        # the engine arithmetic is exact: every reachable texel lands on its target
        assert np.mean(diff == 0) >= 0.99 and diff.max() <= 1, source


def test_level2_flags_texels_a_light_cannot_carry():
    # A narrow 610 nm LED is outside the sRGB gamut: its light colour is clipped
    # (blue 0, green weak), so some samples need more than the light carries.
    led = colour.sd_single_led(610, half_spectral_width=15, shape=WORKING_SHAPE)
    texture = level2_texture(ces99().reflectances, led)
    assert not texture.light.in_gamut and texture.light.rgb8[2] == 0
    assert texture.unreachable.any()
    assert texture.rgb8.max() <= 255 and texture.rgb8.min() >= 0
    # and the reachable ones still land on their target
    out = engine_render(texture.rgb8, texture.light.rgb8)
    ok = ~texture.unreachable
    diff = np.abs(out[ok] - np.round(texture.target_dac[ok]))
    assert np.mean(diff == 0) >= 0.99 and diff.max() <= 1


def test_observers_are_never_mixed():
    from workbench.errors import InputError

    with pytest.raises(InputError, match="characterized for the cie1931-2 observer"):
        light_colour(get_illuminant("cie-d65").sd, observer="cie1964-10")


def test_target_dac_uses_the_display_white():
    bright = SRGBDisplay(Y_white=300.0)
    dac_bright, XYZ_bright = target_dac(np.full(401, 0.5), get_illuminant("cie-d65").sd, bright)
    dac_unit, XYZ_unit = target_dac(np.full(401, 0.5), get_illuminant("cie-d65").sd)
    np.testing.assert_allclose(dac_bright, dac_unit)
    np.testing.assert_allclose(XYZ_bright, 3 * XYZ_unit)
