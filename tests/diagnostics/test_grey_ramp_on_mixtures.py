"""Along dense sweeps, a coarse grey ramp within noise of the paper's model overall is taken where
it predicts the mixtures better, beyond noise and by the materiality floor.

``paper+greys`` sessions of the independent generator: 150 sweep rows, which the paper's power
laws are fitted to and the grey ramp is not, 15 greys 16 DAC apart, the whites and 24 mixtures.
Hidden colours are the peer bench's (:func:`~tests.diagnostics.peer_bench.hidden_score`).
"""

from __future__ import annotations

from tests.diagnostics.independent_generator import PAIRED_FORMS, generate_session
from tests.diagnostics.peer_bench import hidden_score
from workbench.diagnostics import diagnose
from workbench.diagnostics.authors import fit_grey_ramp_linearisation


def _scores(effects, seed):
    """(diagnosis, hidden ΔE00 of the export, of the paper's model, of the authors' method)."""
    generated = generate_session(effects, seed=seed, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    authors = fit_grey_ramp_linearisation(generated.session)
    return (diagnosis,
            hidden_score(generated, diagnosis.extended, diagnosis.white, seed),
            hidden_score(generated, diagnosis.baseline, diagnosis.white, seed),
            hidden_score(generated, authors, diagnosis.white, seed))


def test_a_warm_up_beside_the_sweeps_exports_the_grey_ramp_on_its_mixtures():
    # the grey ramp was within noise of the paper's model overall (0.077 ± 0.053) and better on
    # the 24 mixtures by 0.124 ± 0.019; the paper's model had been exported, 0.246 mean ΔE00 on
    # hidden colours where the seed authors' own method scores 0.178
    diagnosis, exported, paper, authors = _scores(PAIRED_FORMS["warm-up beside sweeps"], 31005)
    assert diagnosis.model_choice.chosen == "grey-ramp", diagnosis.model_choice.reason
    assert "mixtures better" in diagnosis.model_choice.reason
    assert exported < paper - 0.1
    assert exported <= authors + 0.01


def test_a_clean_display_exports_the_grey_ramp_on_its_mixtures():
    # mixtures 0.080 ± 0.033 better; hidden colours 0.197 with the paper's model, the authors'
    # method 0.179
    diagnosis, exported, paper, authors = _scores({}, 33000)
    assert diagnosis.model_choice.chosen == "grey-ramp", diagnosis.model_choice.reason
    assert not [f for f in diagnosis.findings if f.effect != "unexplained-residual"]
    assert exported < paper - 0.05
    assert exported <= authors + 0.01


def test_a_gain_on_the_mixtures_below_the_materiality_floor_keeps_the_paper_model():
    # a clean display of the diagnosis suite: the grey ramp predicts the mixtures better by
    # 0.014 ± 0.006, beyond noise; taken, it lost to the paper's model on the measured validation
    # colours (0.121 → 0.167) and on hidden colours (0.079 → 0.106)
    diagnosis, exported, paper, _ = _scores({}, 600)
    assert diagnosis.model_choice.chosen == "baseline", diagnosis.model_choice.reason
    assert exported == paper
