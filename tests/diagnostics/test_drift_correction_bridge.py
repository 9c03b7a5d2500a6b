"""A drift correction's error is one bend along a sweep, not noise on each level.

The correction ramps between white references; a display that changed at an unknown moment
between two of them leaves every level measured in that interval off by errors that are alike
(a Brownian bridge, :meth:`DriftCorrection.bridge_covariance`). Read as independent, they bent
sweeps into a `tone-curve-shape` and, with a bluish black scaled along, moved the dark points'
chromaticity into a `chromaticity-shift` beside a warm-up or a step that had no such effect.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics import diagnose
from workbench.diagnostics.evidence import DriftCorrection


def test_the_bridge_is_the_uncertainty_on_its_diagonal_and_alike_within_an_interval():
    drift = DriftCorrection(times=np.array([0.0, 100.0, 200.0]), gains=np.array([1.0, 0.98, 0.98]),
                            luminances=np.array([100.0, 98.0, 98.0]))
    t = np.array([25.0, 50.0, 75.0, 150.0])
    covariance = drift.bridge_covariance(t)
    change = 0.02 / 0.99
    u = np.array([0.25, 0.5, 0.75])
    np.testing.assert_allclose(np.diag(covariance)[:3], change ** 2 * u * (1 - u))
    np.testing.assert_allclose(np.sqrt(np.diag(covariance)[:3]), drift.uncertainty(t[:3]))
    assert covariance[0, 2] == pytest.approx(change ** 2 * 0.25 * 0.25)  # u (1 − v)
    assert covariance[3, 3] == 0.0 and np.all(covariance[3, :3] == 0.0)  # steady interval
    assert np.all(np.linalg.eigvalsh(covariance) > -1e-15)


@pytest.mark.parametrize("effects, seed", [
    ({"temporal-drift": "warm-up"}, 30005),
    ({"black-offset": "bluish", "temporal-drift": "step"}, 30005),
    ({"black-offset": "bluish", "temporal-drift": "step"}, 30004),
])
def test_a_drift_beside_the_sweeps_bends_no_tone_curve_and_moves_no_chromaticity(effects, seed):
    diagnosis = diagnose(generate_session(effects, seed=seed, plan="paper").session)
    named = {f.effect for f in diagnosis.findings}
    assert "temporal-drift" in named
    assert not named & {"tone-curve-shape", "chromaticity-shift"}, diagnosis.findings


@pytest.mark.parametrize("seed", [7, 8])
def test_a_shoulder_beside_a_step_is_still_named(seed):
    effects = {"tone-curve-shape": "shoulder", "temporal-drift": "step"}
    diagnosis = diagnose(generate_session(effects, seed=seed, plan="paper").session)
    assert {"tone-curve-shape", "temporal-drift"} <= {f.effect for f in diagnosis.findings}
