"""Hidden-effect tests: APL limiting in a form the model does not share, at seeded random magnitudes."""

import numpy as np
import pytest

from tests.apl.generator import generate_session
from workbench.apl import (apl_fold_labels, detect_apl_dependence, evaluate_apl_holdout, fit_apl_curve)

NOISE = 0.002
Z_FOUND = 5.0  # far beyond any significance threshold over the six detectors (2.39)
SEEDS = range(6)


def _loss(seed):
    return float(np.random.default_rng([10, seed]).uniform(0.15, 0.45))


@pytest.mark.parametrize("seed", SEEDS)
def test_hidden_apl_limiting_is_found(seed):
    test = detect_apl_dependence(generate_session(_loss(seed), seed, NOISE), NOISE)
    assert test.testable
    assert test.z > Z_FOUND, test.evidence
    assert test.impact_dE00 > 1.0
    assert "per unit of the frame's load" in test.evidence


@pytest.mark.parametrize("seed", SEEDS)
def test_curve_predicts_held_out_window_sizes(seed):
    session = generate_session(_loss(seed), seed, NOISE)
    labels = apl_fold_labels(session)
    assert set(labels) == {"window size", "surround level"}
    for by, fold_labels in labels.items():
        score = evaluate_apl_holdout(session, fold_labels, by)
        # the load term must at least halve the held-out luminance error at loads the fit did not see
        assert score.luminance_error_pct < 0.5 * score.luminance_error_pct_without, score.one_line()
        assert score.dE00 < score.dE00_without, score.one_line()
    # the full-field fold: the highest loads, beyond every load the fit saw
    score = evaluate_apl_holdout(session, labels["window size"], "window size")
    (full,) = [fold for fold in score.folds if fold.label == "window 1"]
    assert full.luminance_error_pct < 0.5 * full.luminance_error_pct_without, full


def test_held_out_error_is_small_where_the_fit_interpolates():
    session = generate_session(0.3, 99, NOISE)
    score = evaluate_apl_holdout(session, apl_fold_labels(session)["surround level"], "surround level")
    assert score.luminance_error_pct < 2.0, score.one_line()


@pytest.mark.parametrize("seed", range(20))
def test_clean_sessions_give_no_finding(seed):
    test = detect_apl_dependence(generate_session(0.0, 1000 + seed, NOISE), NOISE)
    assert test.testable
    assert abs(test.z) < 3.5, test.evidence  # |z| > 3.5 has probability 5e-4 per clean session


def test_clean_z_scores_are_standard_normal():
    z = np.array([detect_apl_dependence(generate_session(0.0, 2000 + s, NOISE), NOISE).z for s in range(60)])
    assert abs(z.mean()) < 0.5 and 0.6 < z.std() < 1.4


def test_fitted_curve_falls_with_load():
    curve = fit_apl_curve(generate_session(0.35, 7, NOISE))
    gains = curve.gain([0.0, 0.2, 0.5, 1.0])
    assert np.all(np.diff(gains) <= 1e-12) and gains[0] == pytest.approx(1.0)
    # a full white on a full field relative to the same white alone in a small window
    assert 1 - gains[-1] / gains[0] == pytest.approx(0.35, abs=0.12)
