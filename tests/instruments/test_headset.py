"""The simulated headset: Table 1 colorimetry, additivity, and each physical effect."""

import math

import numpy as np
import pytest

from instruments.headset import (
    HEADSET_EFFECTS,
    TABLE1_HTC_VIVE,
    WARMUP_TAU_FRACTION,
    WAVELENGTHS_NM,
    HeadsetError,
    SimulatedHeadset,
    parse_effect,
    radiance_to_XYZ,
)

FULL = {"r": (255, 0, 0), "g": (0, 255, 0), "b": (0, 0, 255)}
WHITE = (255, 255, 255)


def XYZ(headset, rgb, t_s=0.0):
    return radiance_to_XYZ(headset.radiance(rgb, t_s))


def xy(XYZ_):
    XYZ_ = np.asarray(XYZ_)
    return XYZ_[..., :2] / XYZ_.sum(axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def clean():
    return SimulatedHeadset()


def test_spectral_sampling_is_380_to_780_at_1nm(clean):
    assert np.array_equal(clean.wavelengths, np.arange(380, 781))
    assert clean.radiance(WHITE).shape == (401,)
    assert clean.radiance(np.zeros((5, 3))).shape == (5, 401)


@pytest.mark.parametrize("channel", ["r", "g", "b"])
def test_primaries_have_table1_chromaticity(clean, channel):
    assert np.allclose(xy(XYZ(clean, FULL[channel])), TABLE1_HTC_VIVE.primaries_xy[channel], atol=1e-3)


@pytest.mark.parametrize("channel, peak_range", [("r", (605, 625)), ("g", (520, 540)), ("b", (445, 465))])
def test_primaries_are_narrow_bands_like_fig3(clean, channel, peak_range):
    spectrum = clean.radiance(FULL[channel])
    peak = WAVELENGTHS_NM[np.argmax(spectrum)]
    above_half = WAVELENGTHS_NM[spectrum >= spectrum.max() / 2]
    assert peak_range[0] <= peak <= peak_range[1]
    assert 15 <= above_half.max() - above_half.min() <= 40


@pytest.mark.parametrize("luminance", [100.0, 80.0])
def test_white_has_table1_chromaticity_and_the_requested_luminance(luminance):
    headset = SimulatedHeadset(white_luminance=luminance)
    white = XYZ(headset, WHITE)
    assert np.allclose(xy(white), TABLE1_HTC_VIVE.white_xy, atol=1e-4)
    assert white[1] == pytest.approx(luminance, rel=1e-9)


@pytest.mark.parametrize("channel, index", [("r", 0), ("g", 1), ("b", 2)])
def test_channel_tone_curves_have_table1_gammas(clean, channel, index):
    levels = np.arange(5, 256, 5)
    rgb = np.zeros((len(levels), 3))
    rgb[:, index] = levels
    Y = radiance_to_XYZ(clean.radiance(rgb))[:, 1]
    slope = np.polyfit(np.log(levels / 255), np.log(Y / Y[-1]), 1)[0]
    assert slope == pytest.approx(TABLE1_HTC_VIVE.gammas[channel], abs=1e-6)


def test_clean_headset_is_additive_with_zero_black(clean, rng):
    rgb = rng.integers(0, 256, size=(30, 3)).astype(float)
    singles = sum(clean.radiance(rgb * mask) for mask in np.eye(3))
    assert np.allclose(clean.radiance(rgb), singles, rtol=1e-12, atol=0)
    assert np.all(clean.radiance((0, 0, 0)) == 0)


def test_vectorised_radiance_equals_one_at_a_time(clean, rng):
    headset = SimulatedHeadset({effect: None for effect in HEADSET_EFFECTS})
    rgb = rng.uniform(0, 255, size=(7, 3))
    assert np.allclose(headset.radiance(rgb, 60.0), [headset.radiance(v, 60.0) for v in rgb])


def test_black_offset_emits_the_fraction_of_white_with_table1_black_chromaticity(clean):
    magnitude = 0.008
    headset = SimulatedHeadset({"black-offset": magnitude})
    black = XYZ(headset, (0, 0, 0))
    assert black[1] == pytest.approx(magnitude * 100.0, rel=1e-9)
    assert np.allclose(xy(black), TABLE1_HTC_VIVE.black_xy, atol=1e-4)
    assert np.allclose(XYZ(headset, (128, 30, 200)), XYZ(clean, (128, 30, 200)) + black)


def test_channel_interaction_takes_its_magnitude_off_white_and_spares_single_channels(clean):
    magnitude = 0.12
    headset = SimulatedHeadset({"channel-interaction": magnitude})
    primaries_Y = sum(XYZ(headset, FULL[c])[1] for c in "rgb")
    assert XYZ(headset, WHITE)[1] / primaries_Y == pytest.approx(1 - magnitude, rel=1e-9)
    for channel in "rgb":
        assert np.allclose(XYZ(headset, FULL[channel]), XYZ(clean, FULL[channel]))
    # mixtures fall short in proportion to the load above one channel's
    grey = (180, 180, 180)
    load = (180 / 255) ** np.array([2.43, 2.38, 2.38])
    expected = 1 - magnitude * (load.mean() - 1 / 3) / (2 / 3)
    assert XYZ(headset, grey)[1] / XYZ(clean, grey)[1] == pytest.approx(expected, rel=1e-9)
    dim = (40, 40, 40)
    assert np.allclose(XYZ(headset, dim), XYZ(clean, dim))


@pytest.mark.parametrize("channel", ["r", "g", "b"])
def test_chromaticity_shift_moves_primaries_toward_white_at_low_drive_only(clean, channel):
    magnitude = 0.03
    headset = SimulatedHeadset({"chromaticity-shift": magnitude})
    full = FULL[channel]
    low = tuple(0.01 if v else 0 for v in full)
    primary_xy = xy(XYZ(clean, full))
    shifted_xy = xy(XYZ(headset, low))
    white_xy = np.array(TABLE1_HTC_VIVE.white_xy)
    assert np.hypot(*(shifted_xy - primary_xy)) == pytest.approx(magnitude, rel=1e-3)
    assert np.hypot(*(shifted_xy - white_xy)) < np.hypot(*(primary_xy - white_xy))
    assert np.allclose(XYZ(headset, full), XYZ(clean, full))
    mid = tuple(128 if v else 0 for v in full)
    assert XYZ(headset, mid)[1] == pytest.approx(XYZ(clean, mid)[1], rel=1e-9)  # luminance kept
    assert 0 < np.hypot(*(xy(XYZ(headset, mid)) - primary_xy)) < magnitude


def test_tone_curve_shape_crushes_below_the_threshold_and_restretches_above(clean):
    magnitude = 0.06
    headset = SimulatedHeadset({"tone-curve-shape": magnitude})
    threshold = magnitude * 255
    assert np.all(headset.radiance((threshold - 0.5, threshold - 0.5, threshold - 0.5)) == 0)
    assert XYZ(headset, (0, threshold + 2, 0))[1] > 0
    assert np.allclose(XYZ(headset, WHITE), XYZ(clean, WHITE))
    d = 100 / 255
    expected = ((d - magnitude) / (1 - magnitude)) ** 2.38
    assert XYZ(headset, (0, 100, 0))[1] / XYZ(clean, FULL["g"])[1] == pytest.approx(expected, rel=1e-9)


def test_temporal_drift_warms_up_over_the_session(clean):
    magnitude, session = 0.06, 4000.0
    headset = SimulatedHeadset({"temporal-drift": magnitude}, session_length_s=session)
    tau = WARMUP_TAU_FRACTION * session
    assert headset.warmup_tau_s == pytest.approx(tau)
    white = XYZ(clean, WHITE)[1]
    times = np.array([0.0, 0.5, 1.0, 3.0]) * tau
    Y = np.array([XYZ(headset, WHITE, t)[1] for t in times])
    assert Y[0] == pytest.approx((1 - magnitude) * white, rel=1e-12)
    assert np.all(np.diff(Y) > 0)
    assert Y / white == pytest.approx(1 - magnitude * np.exp(-times / tau), rel=1e-12)
    assert XYZ(headset, WHITE, 20 * tau)[1] == pytest.approx(white, rel=1e-8)


@pytest.mark.parametrize("effect", sorted(HEADSET_EFFECTS))
def test_every_effect_at_a_random_realistic_magnitude_departs_from_the_clean_headset(effect, clean, rng):
    low, high = HEADSET_EFFECTS[effect].realistic_range
    headset = SimulatedHeadset({effect: rng.uniform(low, high)})
    probes = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [255, 255, 255], [200, 100, 50]])
    assert not np.allclose(headset.radiance(probes), clean.radiance(probes))


def test_every_effect_documents_a_default_inside_its_realistic_range():
    for spec in HEADSET_EFFECTS.values():
        low, high = spec.realistic_range
        assert low <= spec.default <= high
        assert spec.limits[0] <= low and high < spec.limits[1]
        assert spec.summary and spec.magnitude


def test_show_and_current_radiance_follow_the_session_clock():
    now = [0.0]
    headset = SimulatedHeadset({"temporal-drift": 0.05}, clock=lambda: now[0])
    assert np.all(headset.current_radiance() == 0)  # black until something is shown
    headset.show([255, 255, 255])
    first = headset.current_radiance()
    now[0] = 10 * headset.warmup_tau_s
    assert radiance_to_XYZ(headset.current_radiance())[1] > radiance_to_XYZ(first)[1]
    assert np.array_equal(headset.shown, [255, 255, 255])


@pytest.mark.parametrize("bad", [(256, 0, 0), (-1, 0, 0), (math.nan, 0, 0), (1, 2), [[1, 2, 3, 4]]])
def test_bad_dac_values_are_refused_with_the_fix(clean, bad):
    with pytest.raises(ValueError, match="0..255|3 DAC values"):
        clean.radiance(bad)


def test_a_seeded_unit_is_reproducible_and_within_table1_spread():
    a, b, c = SimulatedHeadset(seed=11), SimulatedHeadset(seed=11), SimulatedHeadset(seed=12)
    assert np.array_equal(a.radiance(WHITE), b.radiance(WHITE))
    assert not np.array_equal(a.radiance(FULL["r"]), c.radiance(FULL["r"]))
    for channel in "rgb":
        sd = np.array(TABLE1_HTC_VIVE.primaries_xy_sd[channel])
        measured = xy(XYZ(a, FULL[channel]))
        assert np.all(np.abs(measured - TABLE1_HTC_VIVE.primaries_xy[channel]) < 5 * sd + 1e-3)


def test_parse_effect_reads_id_and_magnitude_or_takes_the_default():
    assert parse_effect("channel-interaction:0.1") == ("channel-interaction", 0.1)
    assert parse_effect("black-offset") == ("black-offset", HEADSET_EFFECTS["black-offset"].default)


@pytest.mark.parametrize("text, message", [
    ("sparkle:0.1", "unknown headset effect 'sparkle'; use one of black-offset, channel-interaction"),
    ("black-offset:lots", "not a number"),
    ("tone-curve-shape:1.5", "outside"),
    ("channel-interaction:-0.1", "outside"),
])
def test_parse_effect_errors_say_what_to_write(text, message):
    with pytest.raises(HeadsetError, match=message):
        parse_effect(text)


def test_a_chromaticity_shift_as_far_as_white_is_refused():
    with pytest.raises(HeadsetError, match="chromaticity-shift.*outside"):
        SimulatedHeadset({"chromaticity-shift": 0.3})
