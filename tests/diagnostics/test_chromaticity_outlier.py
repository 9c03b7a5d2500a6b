"""A chromaticity shift must hold without the sweep's most deviant point: one reading is not a shift.

A heavy-tailed instrument reads one dark sweep point's xy a few σ off now and then; at the dark
end, where the shift's quadratic has its leverage, that one reading made a shift (on fresh
peer-bench seeds 59000–59009, the paper plan: a red sweep beside every drift form of one
display, a green one beside an S-curve and a soft toe of another). A real shift moves every dark
point along a smooth path and holds without any one of them.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics import diagnose
from workbench.diagnostics.detectors import _chromaticity_test, _robust_chromaticity_test
from workbench.diagnostics.significance import critical_p

LEVEL = critical_p(5)  # the five detectors of a session without APL rows


@pytest.mark.parametrize("effects, seed, channel", [
    ({"temporal-drift": "warm-up"}, 59007, 0),
    ({"tone-curve-shape": "s-curve"}, 59002, 1),
])
def test_one_dark_reading_off_is_no_chromaticity_shift(effects, seed, channel):
    diagnosis = diagnose(generate_session(effects, seed=seed, plan="paper").session)
    assert "chromaticity-shift" not in {f.effect for f in diagnosis.findings}
    sweep = diagnosis.context.sweeps[channel]
    every_point = _chromaticity_test(sweep, diagnosis.context)
    # with every point the channel's test is beyond the family's level (three channels): the
    # one reading decides, and it is a reading a heavy-tailed instrument gives (under 8σ)
    assert 3 * every_point[0] < LEVEL
    index, sigmas = every_point[6]
    assert sigmas < 8.0 and sweep.drive[index] < 0.3
    assert 3 * _robust_chromaticity_test(sweep, diagnosis.context)[0] > LEVEL


@pytest.mark.parametrize("form", ["leak", "log-desaturation"])
def test_a_real_shift_holds_without_any_one_point(form):
    # a shift of the independent generator's, its size drawn by the seed, moves every dark point
    found = []
    for seed in range(59000, 59004):
        diagnosis = diagnose(generate_session({"chromaticity-shift": form}, seed=seed,
                                              plan="paper").session)
        found.append("chromaticity-shift" in {f.effect for f in diagnosis.findings})
        tests = [_robust_chromaticity_test(s, diagnosis.context) for s in diagnosis.context.sweeps]
        p = min(t[0] for t in tests if t is not None)
        assert 3 * p < LEVEL, (seed, p)
    assert all(found)
