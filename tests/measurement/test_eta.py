"""The remaining-time estimate knows dark patches take longer."""

import pytest

from workbench.measurement.eta import PatchDurationModel
from workbench.measurement.plans import Patch

BLACK, WHITE = Patch("black", (0, 0, 0)), Patch("white", (255, 255, 255))


def test_nothing_is_predicted_before_a_patch_was_measured():
    model = PatchDurationModel()
    assert model.remaining_s([WHITE]) is None and model.patch_s(WHITE) is None
    model.observe(BLACK, 0.0, 30.0)
    assert model.remaining_s([WHITE, WHITE]) == pytest.approx(60.0)  # one observation: that is all it knows
    assert model.remaining_s([]) == 0.0


def test_dark_patches_are_predicted_to_take_longer():
    model = PatchDurationModel()
    model.observe(BLACK, 0.0, 250.0)
    model.observe(WHITE, 100.0, 3.0)
    model.observe(Patch("ramp-g", (0, 128, 0)), 15.0, 4.0)
    dark, mid, bright = (model.patch_s(Patch("ramp-g", (0, v, 0))) for v in (5, 60, 255))
    assert dark > mid > bright >= 3.0
    assert model.patch_s(Patch("white", (255, 255, 255))) == pytest.approx(3.0)


def test_measured_primaries_replace_the_prior_channel_shares():
    model = PatchDurationModel()
    model.observe(WHITE, 100.0, 3.0)
    model.observe(Patch("ramp-b", (0, 0, 255)), 7.0, 20.0)
    assert model.channel_shares()[2] == pytest.approx(0.07)
    assert model.expected_relative_luminance(Patch("ramp-b", (0, 0, 255))) == pytest.approx(0.07)


def test_a_failed_patch_is_placed_by_its_expected_luminance():
    model = PatchDurationModel()
    model.observe(WHITE, 100.0, 3.0)
    model.observe(BLACK, None, 240.0)
    assert model.patch_s(BLACK) == pytest.approx(240.0)
