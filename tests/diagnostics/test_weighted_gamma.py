"""The paper's model with noise-weighted gammas, chosen by cross-validation where it predicts better.

On a plan with about ten sweep levels a channel (the adaptive plan's core), the baseline's γ,
fitted in luminance, is decided by the brightest levels, whose noise is the largest in absolute
terms, and a few tenths of a percent on two of them tilt the whole curve. The ``weighted-gamma``
candidate (:data:`~workbench.diagnostics.model_choice.WEIGHTED_CANDIDATES`) fits each γ with the
instrument's noise weights and replaces the baseline where it lowers the cross-validated error
beyond noise, on sparse sweeps (:data:`~workbench.diagnostics.model_choice.SPARSE_SWEEP_LEVELS`).

The sessions come from the independent generator (its own noise: a t-distributed gain, a
per-coordinate part, shot noise and a dark floor), clean, measured on ``paper+greys`` with the
sweeps thinned to eleven levels a channel; the score is on hidden colours from the true display.
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session, hidden_colours
from workbench.colorimetry import delta_E2000
from workbench.diagnostics import diagnose
from workbench.display import GammaMatrixDisplay
from workbench.profile import profile_from_diagnosis

LEVELS = (30, 65, 95, 130, 160, 190, 210, 225, 235, 245, 255)
SEEDS = range(6)


def _thinned(seed):
    generated = generate_session(None, seed=seed, noise=0.003, plan="paper+greys")
    session = generated.session
    sweep = session.mask("ramp-r", "ramp-g", "ramp-b")
    keep = ~sweep | np.isin(session.rgb.max(axis=1), LEVELS)
    return generated, session.subset(keep)


@pytest.fixture(scope="module")
def diagnosed():
    out = []
    for seed in SEEDS:
        generated, session = _thinned(seed)
        rgb = hidden_colours(300, seed)
        truth = generated.display.light(rgb)
        diagnosis = diagnose(session)
        exported = delta_E2000(diagnosis.extended.forward(rgb), truth, diagnosis.white).mean()
        baseline = delta_E2000(diagnosis.baseline.forward(rgb), truth, diagnosis.white).mean()
        out.append((diagnosis, float(exported), float(baseline)))
    return out


def test_weighted_gamma_replaces_the_baseline_where_it_predicts_better(diagnosed):
    chosen = [d.model_choice.chosen for d, _, _ in diagnosed]
    assert chosen.count("weighted-gamma") >= 4, chosen
    exported = np.mean([e for _, e, _ in diagnosed])
    baseline = np.mean([b for _, _, b in diagnosed])
    assert exported < 0.75 * baseline, (exported, baseline)
    for diagnosis, e, b in diagnosed:  # never worse than the baseline beyond noise
        assert e <= b + 0.02, (diagnosis.model_choice.reason, e, b)


def test_the_weighted_model_is_the_papers_form_and_exports(diagnosed):
    diagnosis = next(d for d, _, _ in diagnosed if d.model_choice.chosen == "weighted-gamma")
    assert isinstance(diagnosis.extended, GammaMatrixDisplay)
    np.testing.assert_allclose(diagnosis.extended.matrix, diagnosis.baseline.matrix)
    assert not np.allclose(diagnosis.extended.gamma, diagnosis.baseline.gamma)
    document = diagnosis.to_json()
    assert document["model_choice"]["chosen"] == "weighted-gamma"
    assert "noise weights" in document["model_choice"]["description"]
    assert "weighted-gamma predicts unseen fit rows better than the baseline" in \
        document["model_choice"]["reason"]
    assert all(not f["in_model"] for f in document["findings"])  # no effect's term in it
    profile = profile_from_diagnosis(diagnosis)
    rgb = np.array([[10.0, 120.0, 250.0], [200.0, 30.0, 90.0]])
    np.testing.assert_allclose(profile.display_model().forward(rgb), diagnosis.extended.forward(rgb))


def test_on_the_paper_plans_dense_sweeps_the_papers_fit_stands():
    """51 levels a channel: the weighted candidates are not tried (SPARSE_SWEEP_LEVELS)."""
    generated = generate_session(None, seed=1, noise=0.003, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    assert diagnosis.model_choice.chosen == "baseline"
    assert not set(diagnosis.model_choice.cv_mean_dE00) & {"weighted-gamma", "weighted-gamma+greys"}
