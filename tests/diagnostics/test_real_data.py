"""Real displays: the extension never worse than the baseline, drift named first, and Argyll as the peer."""

import pytest

from tests.test_diagnostics import REAL, needs_real_data
from workbench.diagnostics.argyll import argyll_missing

needs_argyll = pytest.mark.skipif(argyll_missing() is not None,
                                  reason=f"argyll: {argyll_missing()}")
LCD = REAL / "lcd-ti3"
TI3 = ["dell-up2516d-displaycal.ti3", "monitor-displaycal.ti3",
       "lcd-ti3/Apple_MacBookPro13-Late2013_2018-06-03_1459_i1d3_175p.ti3",
       "lcd-ti3/HP_EliteBook835G7_2020-09-28_2130_i1d3_588p.ti3",
       "lcd-ti3/KOIOS_K2418U_2019-04-01_1518_i1d3_417p.ti3",
       "lcd-ti3/Microsoft_SurfacePro3-120QL01-001_2019-02-19_0841_i1d3_175p.ti3"]


@needs_real_data
@pytest.mark.parametrize("name", ["Apple_MacBookPro13-Late2013_2018-06-03_1459_i1d3_175p.ti3",
                                  "HP_EliteBook835G7_2020-09-28_2130_i1d3_588p.ti3"])
def test_drifting_and_unstable_displays_name_drift_before_what_it_could_masquerade_as(name):
    from workbench.diagnostics import diagnose
    from workbench.session_readers import read_session

    diagnosis = diagnose(read_session(LCD / name))
    names = [f.effect for f in diagnosis.findings]
    assert names[0] == "temporal-drift", names
    drift = diagnosis.findings[0]
    assert "row order" in drift.evidence
    assert any("row order" in why for _, why in diagnosis.untested)


@needs_real_data
@pytest.mark.slow
@pytest.mark.parametrize("name", TI3)
def test_no_extension_is_worse_than_the_baseline_and_ours_beats_argyll(name):
    from workbench.diagnostics.real_data import _row

    row = _row(REAL / name, REAL, with_argyll=argyll_missing() is None)
    assert not row.error
    assert row.extended_not_worse
    if argyll_missing() is None:
        assert row.beats_argyll, (row.best_ours, row.argyll)


@needs_real_data
@needs_argyll
def test_argyll_peer_fits_the_same_rows_and_scores_the_same_held_out_colours(tmp_path):
    import numpy as np

    from workbench.diagnostics.argyll import fit_argyll_shaper_matrix, score_argyll
    from workbench.session_readers import read_session

    session = read_session(REAL / "dell-up2516d-displaycal.ti3")
    fit_rows = session.without("validation")
    profile = fit_argyll_shaper_matrix(fit_rows, tmp_path)
    written = (tmp_path / "fit.ti3").read_text()
    assert f"NUMBER_OF_SETS {len(fit_rows)}" in written  # exactly the fit rows
    # absolute: the profile's white is the measured white in cd/m²
    white = profile.forward(np.array([[255.0, 255.0, 255.0]]))[0]
    np.testing.assert_allclose(white[1], session.white_XYZ[1], rtol=0.01)
    score = score_argyll(session)
    assert score.n == 108 and 0.1 < score.mean_dE00 < 1.0 and not score.unavailable


def test_argyll_missing_says_so(monkeypatch):
    import shutil

    from workbench.diagnostics import argyll
    from workbench.session import Session

    monkeypatch.setattr(shutil, "which", lambda name: None)
    score = argyll.score_argyll(Session(kind=["white"], rgb=[[255, 255, 255]], XYZ=[[95, 100, 108]]))
    assert score.mean_dE00 is None and "argyll" in score.unavailable


@needs_real_data
def test_a_real_lcd_without_its_greys_takes_the_crosstalk_shape_and_keeps_most_of_the_gain():
    # the KOIOS's white departs from R+G+B channel by channel (its own shortfalls −29, −41 and
    # +9 %); with its greys the shape is fitted (exponent 0.5), without them it is taken
    from workbench.diagnostics import diagnose
    from workbench.diagnostics.extension import CROSSTALK_EXPONENT
    from workbench.session_readers import read_session

    session = read_session(LCD / "KOIOS_K2418U_2019-04-01_1518_i1d3_417p.ti3")
    without_greys = session.subset(session.kind != "grey")
    diagnosis = diagnose(without_greys)
    finding = next(f for f in diagnosis.findings if f.effect == "channel-interaction")
    assert finding.in_model and "channel by channel" in finding.evidence
    assert diagnosis.extended.interaction.exponent == CROSSTALK_EXPONENT
    # the conservative shape kept 5.3 of the baseline's 6.2 mean ΔE00; this one about half
    assert diagnosis.extended_score.mean_dE00 < 0.6 * diagnosis.baseline_score.mean_dE00


@needs_real_data
def test_a_grey_ramp_chosen_on_drift_corrected_rows_drops_a_correction_that_does_not_serve_it():
    """The unstable HP chart's four whites (drift on row order, z 2.6): term selection keeps the
    correction for the extension, but the grey ramp chosen over it predicts the fit rows better
    from the rows as measured, and is exported from them (2.59 mean ΔE00 on the held-out
    mixtures; from the corrected rows 2.75, behind the seed authors' method's 2.71)."""
    from workbench.diagnostics import diagnose
    from workbench.diagnostics.real_data import _row
    from workbench.session_readers import read_session

    name = "HP_EliteBook835G7_2020-09-28_2130_i1d3_588p.ti3"
    diagnosis = diagnose(read_session(LCD / name))
    assert diagnosis.model_choice.chosen == "grey-ramp"
    assert "fitted on the rows as measured" in diagnosis.model_choice.reason
    drift = next(f for f in diagnosis.findings if f.effect == "temporal-drift")
    assert not drift.in_model and "not in the exported model" in drift.cross_validation
    row = _row(LCD / name, REAL, with_argyll=False)
    assert row.extended["mean_dE00"] <= row.authors["mean_dE00"] + 0.02


@needs_real_data
def test_a_correction_term_selection_left_out_comes_back_for_a_grey_ramp_only_beyond_noise():
    """The Surface Pro 3 chart (drift on row order, z 4.9): term selection leaves the correction
    out; the grey ramp chosen over the extension predicts the fit rows better with it by 0.138 ±
    0.072, within noise, so it stays out (taken back, the export scored 1.59 mean ΔE00 on the 108
    held-out colours, 1.41 from the rows as measured, the seed authors' method 1.41)."""
    from workbench.diagnostics import diagnose
    from workbench.diagnostics.real_data import _row
    from workbench.session_readers import read_session

    name = "Microsoft_SurfacePro3-120QL01-001_2019-02-19_0841_i1d3_175p.ti3"
    diagnosis = diagnose(read_session(LCD / name))
    assert diagnosis.context.time_basis == "row order"
    assert diagnosis.model_choice.chosen == "grey-ramp"
    assert not diagnosis.context.drift_found and not diagnosis.model_choice.drift_corrected
    assert "scored on drift-corrected rows" not in diagnosis.model_choice.reason
    drift = next(f for f in diagnosis.findings if f.effect == "temporal-drift")
    assert not drift.in_model
    row = _row(LCD / name, REAL, with_argyll=False)
    assert row.extended["mean_dE00"] <= row.authors["mean_dE00"] + 0.02
