"""A drift found on measurement times stays in the model unless it predicts worse beyond noise.

Sessions from the independent generator (out-of-sample seeds of the peer bench and the
diagnosis suite).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tests.diagnostics.independent_generator import generate_session
from tests.diagnostics.peer_bench import hidden_score
from workbench.diagnostics import diagnose
from workbench.diagnostics.authors import fit_grey_ramp_linearisation
from workbench.diagnostics.model_choice import GREY_RAMP_CANDIDATES


def _hidden_scores(generated, diagnosis, seed):
    """Mean ΔE00 on 300 hidden colours: the exported profile's and the seed authors' method's."""
    authors = fit_grey_ramp_linearisation(generated.session)
    return (hidden_score(generated, diagnosis.extended, diagnosis.white, seed),
            hidden_score(generated, authors, diagnosis.white, seed))


def test_a_plain_drift_on_measurement_times_stays_within_noise():
    # a warm-up during the sweeps, found at z 6.8: its correction was left out on a
    # cross-validated gain of -0.012 ± 0.022 and the paper's model from the uncorrected rows
    # scored 0.155 ΔE00 on hidden colours against the authors' 0.128
    generated = generate_session({"temporal-drift": "warm-up"}, seed=32001, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    note = diagnosis.cross_validation["by_effect"]["temporal-drift"]
    assert note.startswith("in the model"), note
    ours, authors = _hidden_scores(generated, diagnosis, 32001)
    assert ours <= authors + 0.01, (ours, authors)


def test_a_drift_on_row_order_must_still_lower_the_error():
    # the same warm-up with its times taken away: the rows' order stands in for time
    generated = generate_session({"temporal-drift": "warm-up"}, seed=32001, plan="paper+greys")
    session = replace(generated.session, t_s=None)
    diagnosis = diagnose(session)
    assert diagnosis.context.time_basis == "row order"
    note = diagnosis.cross_validation["by_effect"].get("temporal-drift", "")
    assert not note.startswith("in the model: a drift found on measurement times"), note


def test_a_drift_found_near_the_critical_value_must_still_lower_the_error():
    # the diagnosis suite's backlight display with no drift, where the drift test fired at
    # z 2.57: kept within noise, the correction took the held-out error from 0.396 to 0.460
    generated = generate_session({"channel-interaction": "backlight"}, seed=106)
    diagnosis = diagnose(generated.session)
    drift = next(r for r in diagnosis.results if r.effect == "temporal-drift")
    assert drift.found and drift.z < 4.0
    note = diagnosis.cross_validation["by_effect"]["temporal-drift"]
    assert note.startswith("left out of the model"), note


def test_the_baseline_must_beat_a_settled_drift_beyond_noise_to_replace_it():
    # a warm-up during the sweeps on the seed authors' own plan, found at z 7.3: the drift stayed
    # in term selection, then the extension that held it lost to the paper's model from the
    # uncorrected rows on a gain of -0.039 ± 0.032 and was dropped with it; exported, the
    # paper's model scored 0.236 ΔE00 on hidden colours against the authors' 0.142
    generated = generate_session({"temporal-drift": "warm-up"}, seed=33005, plan="authors-2024")
    diagnosis = diagnose(generated.session)
    assert diagnosis.cross_validation["use_extension"]
    note = diagnosis.cross_validation["by_effect"]["temporal-drift"]
    assert not note.startswith("not used"), note
    ours, authors = _hidden_scores(generated, diagnosis, 33005)
    assert ours <= authors + 0.01, (ours, authors)


def test_a_warm_up_that_bends_at_its_second_white_leaves_the_later_whites_smooth():
    # a held-out peer session: a warm-up during the sweeps, 4.4 % between the first two whites
    # and flat after them, found at z 13.7. One smoothing strength for the whole drift curve
    # followed that bend and copied ±0.3 % of the later whites' noise into the greys; term
    # selection then left the correction out, and the paper's model was exported at 0.099 ΔE00
    # on hidden colours against the authors' 0.080. With a free kink at the bend the curve is
    # smooth after it, the correction serves, and the grey ramp scored 0.030. Since the plan
    # measures its greys last the same display exports the extension with the correction, 0.042
    # against the authors' 0.107
    generated = generate_session("warm-up beside sweeps", seed=55000, plan="authors-2024")
    diagnosis = diagnose(generated.session)
    drift = diagnosis.context.drift
    late = drift.times > 1000
    assert np.ptp(drift.smoothed[late]) < 0.5 * np.ptp(drift.gains[late])
    assert next(r for r in diagnosis.results if r.effect == "temporal-drift").in_model
    ours, authors = _hidden_scores(generated, diagnosis, 55000)
    assert ours <= authors + 0.01, (ours, authors)


def test_a_grey_ramp_competes_on_drift_corrected_rows_where_term_selection_left_them():
    # a held-out peer session: a warm-up during the sweeps on `paper+greys`, whose extension with
    # the correction lost to the paper's model. The grey ramp had been scored on the rows as
    # measured only (0.279 cross-validated against the paper's model's 0.235) and the paper's
    # model was exported: 0.113 ΔE00 on hidden colours (the authors' 0.133). On corrected rows it
    # predicts them better (0.230, a gain of 0.049 ± 0.010) and ties the paper's model, the
    # mixtures breaking the tie: 0.050
    generated = generate_session("warm-up beside sweeps", seed=49008, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    assert not diagnosis.cross_validation["use_extension"]
    assert diagnosis.model_choice.chosen in GREY_RAMP_CANDIDATES, diagnosis.model_choice.reason
    assert diagnosis.model_choice.drift_corrected and diagnosis.context.drift_found
    assert "scored on drift-corrected rows" in diagnosis.model_choice.reason
    drift = next(r for r in diagnosis.results if r.effect == "temporal-drift")
    assert drift.in_model
    ours, authors = _hidden_scores(generated, diagnosis, 49008)
    assert ours <= authors - 0.05 and ours < 0.6 * hidden_score(
        generated, diagnosis.baseline, diagnosis.white, 49008), ours


def test_a_grey_ramp_takes_back_a_correction_that_term_selection_dropped():
    # a held-out peer session: a bluish black and a 7.2 % step that fell 8 s after the white at
    # 701 s, between the green sweep's last two levels, and the next white at 1098 s. The
    # correction's ramp across that interval puts the green primary 7 % off, so the extension
    # predicts the fit rows worse with it and term selection dropped it; the sweep correction
    # chosen then was fitted on rows of two display states and scored 0.624 ΔE00 on hidden colours
    # against the authors' 0.119. Its own cross-validation wants the correction
    generated = generate_session("bluish + step", seed=54006, plan="authors-2024")
    diagnosis = diagnose(generated.session)
    assert "temporal-drift" not in diagnosis.cross_validation["steps"][-1]["terms"]
    assert diagnosis.model_choice.chosen in GREY_RAMP_CANDIDATES, diagnosis.model_choice.reason
    assert diagnosis.context.drift_found
    drift = next(r for r in diagnosis.results if r.effect == "temporal-drift")
    assert diagnosis.model_choice.drift_corrected
    assert drift.in_model and "scored on drift-corrected rows" in drift.cross_validation
    ours, authors = _hidden_scores(generated, diagnosis, 54006)
    assert ours <= authors + 0.01, (ours, authors)
