"""The drift test's smooth trend must hold without a first white read a few σ low, and without a
last white read off alone.

A heavy-tailed instrument reads one white 2.5–4σ off now and then; at the session's start it
has an endpoint's leverage on a low-degree trend, and it read as "a step up" on displays with
no drift (the peer bench, one display's noise in four scenarios). A fast warm-up puts its
first reference farther off than that, and the rest rise with it: it is still found. At the
session's end no warm-up speaks for a lone reading far off: the last white alone, up to
:data:`OUTLIER_SIGMA` off, must not be the whole trend (one heavy-tailed reading 5σ high at the
end made a display with no drift "a rise" on fresh peer-bench seeds); a change the last two
references both show is still one.
"""

from __future__ import annotations

import numpy as np
import pytest

from workbench.diagnostics.detectors import (
    DRIFT_TREND_DEGREE,
    OUTLIER_SIGMA,
    TREND_OUTLIER_SIGMA,
    _trend_chi2,
    detect_temporal_drift_raw,
)
from workbench.diagnostics.evidence import DriftCorrection
from workbench.diagnostics.noise import NoiseModel
from workbench.diagnostics.significance import chi2_sf, critical_p

LEVEL = critical_p(5)  # the five detectors of a session without APL rows

SD = 0.004  # relative repeatability of one white reading
TIMES = np.array([48.0, 544, 649, 999, 1103, 1881, 2046, 2199, 2304, 2409, 2481])


def _result(relative):
    relative = np.asarray(relative, dtype=float)
    white_Y = 100.0
    noise = NoiseModel(gain_sd=SD, xy_sd=0.0002, floor=1e-6, white_Y=white_Y,
                       white_xy=(0.3127, 0.329), source="test", dof=200.0)
    gains = relative / relative[-2:].mean()
    return detect_temporal_drift_raw(DriftCorrection(TIMES, gains, white_Y * relative), "time",
                                     noise)


def _steady(rng):
    return 1.0 + 0.3 * SD * rng.standard_normal(TIMES.size)


@pytest.mark.parametrize("sigmas", [3.9])
def test_a_first_white_a_few_sigma_low_is_no_drift(sigmas):
    assert sigmas < TREND_OUTLIER_SIGMA
    relative = _steady(np.random.default_rng(7))
    relative[0] = np.median(relative) - sigmas * SD
    result = _result(relative)
    assert result.p_value > LEVEL, result.evidence
    # with that reading the trend alone is beyond the level: leaving it out is what decides
    sd = SD * relative
    assert chi2_sf(_trend_chi2(TIMES, relative, sd, DRIFT_TREND_DEGREE),
                   DRIFT_TREND_DEGREE) < LEVEL / 2


def test_a_fast_warm_up_is_still_found():
    relative = _steady(np.random.default_rng(8))
    relative[:3] -= np.array([9.0, 3.0, 1.5]) * SD  # rising, then settled
    result = _result(relative)
    assert result.p_value < LEVEL, result.evidence


def test_a_rise_after_the_first_reference_alone_is_not_called_a_step_without_saying_it_may_be_a_warm_up():
    # one change, between the first two references 500 s apart: a step, or a warm-up that settled
    # before the second reference; nothing between them tells which, so the form says both
    relative = np.full(TIMES.size, 1.0)
    relative[0] = 0.95
    result = _result(relative)
    assert result.details["form"].startswith("a step up after the first reference")
    assert "or a warm-up" in result.details["form"] and "or a warm-up" in result.evidence
    # the same change later in the session is a step (a display does not warm up halfway)
    later = np.where(np.arange(TIMES.size) < 6, 0.95, 1.0)
    assert _result(later).details["form"] == "a step up"
    # and a fall after the first reference is a step down
    assert _result(np.where(np.arange(TIMES.size) < 1, 1.05, 1.0)).details["form"] == "a step down"


def test_a_last_white_read_far_off_alone_is_no_drift():
    rng = np.random.default_rng(59007)
    trend_alone_found = 0
    for _ in range(10):
        sigmas = rng.uniform(TREND_OUTLIER_SIGMA + 0.5, OUTLIER_SIGMA - 0.5)
        relative = _steady(rng)
        relative[-1] = np.median(relative) + rng.choice([-1, 1]) * sigmas * SD
        result = _result(relative)
        assert result.p_value > LEVEL, (sigmas, result.evidence)
        trend = _trend_chi2(TIMES, relative, SD * relative, DRIFT_TREND_DEGREE)
        trend_alone_found += chi2_sf(trend, DRIFT_TREND_DEGREE) < LEVEL / 2
    # with that reading the trend alone is beyond the level on most draws: leaving it out decides
    assert trend_alone_found >= 5


def test_a_change_the_last_two_whites_show_is_still_a_drift():
    rng = np.random.default_rng(59008)
    for _ in range(10):
        relative = _steady(rng)
        relative[-2:] += rng.choice([-1, 1]) * rng.uniform(8.0, 12.0) * SD
        result = _result(relative)
        assert result.p_value < LEVEL, result.evidence
