"""What the Fit & diagnose page shows is taken from the diagnosis generically (no Qt needed)."""

from pathlib import Path

import numpy as np
import pytest

from workbench.gui import diagnosis_views as views
from workbench.workspace import load_path

PROFILE = Path(__file__).resolve().parents[2] / "profiles" / "htc-vive-paper.vrprofile.json"


class _Diagnosis:
    """A stand-in whose to_json has fields the real diagnosis does not have (yet)."""

    def __init__(self, document):
        self._document = document

    def to_json(self):
        return self._document


def test_a_finding_card_carries_every_field_the_finding_has_and_entries_naming_its_effect():
    document = {
        "findings": [{"effect": "future-effect", "evidence": "it is there", "z": 4.25, "impact_dE00": 0.5}],
        "extended": {"terms": [{"effect": "future-effect", "term": "a new term"}]},
        "noise": {"relative_sd_Y": 0.001},
    }
    card, = views.finding_cards(_Diagnosis(document))
    assert card.effect == "future-effect" and card.evidence == "it is there"
    # the statistics the card knows read as one line; any other field is shown as it is
    assert dict(card.fields) == {"test": "z 4.2 · impact 0.50 ΔE00 on the fixed colours",
                                 "extended.terms: term": "a new term"}
    assert card.plot is None  # no plot is registered for an effect the page does not know
    assert ("noise", "relative_sd_Y 0.001") in views.detail_lines(_Diagnosis(document))


def test_the_views_of_a_real_diagnosis_have_labelled_axes_and_the_diagnosis_own_numbers():
    diagnosis = load_path(PROFILE).diagnosis
    sweeps = views.sweep_views(diagnosis)
    assert len(sweeps) == 3 and all(v.fit.x_label == "DAC" and "%" in v.residuals.y_label for v in sweeps)
    additivity = views.additivity_view(diagnosis)
    expected = 100 * (diagnosis.context.white - diagnosis.context.black) / sum(
        s.full_XYZ for s in diagnosis.context.sweeps)
    assert np.allclose(additivity.series[0].y, expected) and additivity.series[0].bars
    assert [label for _, label in additivity.x_ticks] == ["X", "Y", "Z"]
    assert views.white_reference_view(diagnosis) is None  # a profile has no white references over time
    found = [f["effect"] for f in diagnosis.to_json()["findings"]]
    assert [c.effect for c in views.finding_cards(diagnosis)] == found


def test_srgb_swatches_show_the_display_white_as_white_and_clip_what_is_outside():
    white = np.array([95.0, 100.0, 108.0])
    assert views.XYZ_to_srgb8(white, white).tolist() == [255, 255, 255]
    assert views.XYZ_to_srgb8(np.zeros(3), white).tolist() == [0, 0, 0]
    assert views.XYZ_to_srgb8(np.array([10.0, 60.0, 5.0]), white).tolist()[0] == 0  # red below 0: clipped


@pytest.mark.parametrize("summary", ["session", "baseline", "extended"])
def test_the_verdict_names_session_and_both_models(summary):
    diagnosis = load_path(PROFILE).diagnosis
    assert summary in dict(views.summary_lines(diagnosis))


def test_a_checked_effect_reads_as_its_test_and_its_evidence():
    record = {"effect": "temporal-drift", "evidence": "the whites vary by 0.3 %", "score": -0.4,
              "statistic": 0.0032, "standard_error": 0.0015, "z": -0.86, "p_value": 0.81,
              "critical_z": 2.33, "threshold": 0.0036, "impact_dE00": None, "significant": False,
              "testable": True, "in_model": False, "cross_validation": "", "form": "warm-up"}
    (name, text), = views.detail_lines(_Diagnosis({"checked": [record]}))
    assert name == "checked"
    assert text == ("temporal-drift: z -0.9 < 2.33 (family-wise 5 %), p 0.81 · statistic 0.0032 ± 0.0015"
                    " · not in the model — the whites vary by 0.3 % (form warm-up)")


@pytest.fixture(scope="module")
def knee_diagnosis():
    """A power limit past a knee: tone-curve-shape is channel-interaction's consequence, and the
    power-limit model is exported."""
    from tests.diagnostics.independent_generator import generate_session
    from workbench.diagnostics import diagnose

    return diagnose(generate_session({"channel-interaction": "knee"}, seed=101, plan="paper").session)


def test_a_consequence_card_names_its_cause_and_says_why_once(knee_diagnosis):
    cause, consequence = views.finding_cards(knee_diagnosis)
    assert (cause.effect, consequence.effect) == ("channel-interaction", "tone-curve-shape")
    assert cause.consequence_of == "" and cause.consequences == ("tone-curve-shape",)
    assert consequence.consequence_of == "channel-interaction"
    assert consequence.consequence.startswith("the bend that channel-interaction's power limit")
    assert "a consequence of" not in consequence.evidence and consequence.evidence.startswith("the green sweep")
    assert "consequence_of" not in dict(consequence.fields)  # the card's tag says it
    # each finding's cross-validation note points at the exported model instead of repeating its reason
    reason = views.model_choice_reason(knee_diagnosis)
    assert reason and all(reason not in text for card in (cause, consequence) for _, text in card.fields)
    assert dict(cause.fields)["cross_validation"] == (
        "in the model through the power-limit model (why: see the exported model above)")


def test_the_model_choice_rows_mark_the_exported_model(knee_diagnosis):
    rows = views.model_choice_rows(knee_diagnosis)
    choice = knee_diagnosis.model_choice.to_json()
    assert [r.candidate for r in rows] == list(choice["cv_mean_dE00"])
    assert [r.candidate for r in rows if r.chosen] == ["power-limit"]
    assert all(r.cv_mean_dE00 == pytest.approx(choice["cv_mean_dE00"][r.candidate]) and r.description
               for r in rows)
    assert dict(views.summary_lines(knee_diagnosis))["exported"].startswith("power-limit, the best of 3")
    assert "model_choice" not in dict(views.detail_lines(knee_diagnosis))  # its own table, not a line


def test_a_record_repeated_elsewhere_in_the_json_is_not_listed_twice_on_its_card():
    record = {"effect": "unexplained-residual", "evidence": "a gap", "z": 3.0, "consequence_of": None}
    card, = views.finding_cards(_Diagnosis({"findings": [record], "unexplained": dict(record)}))
    assert not any(name.startswith("unexplained") for name, _ in card.fields)


@pytest.mark.parametrize("effects, corrected", [({"temporal-drift": "step"}, True), ({}, False)])
def test_the_white_references_show_the_correction_as_applied(effects, corrected):
    from tests.diagnostics.independent_generator import generate_session
    from workbench.diagnostics import diagnose

    generated = generate_session(effects, seed=51001, plan="authors-2024", noise=0.002)
    diagnosis = diagnose(generated.session)
    drift = diagnosis.context.drift
    assert diagnosis.context.drift_found is corrected
    series = views.white_reference_view(diagnosis).series
    assert series[0].name == "white" and np.allclose(series[0].y, 100 * drift.gains)
    if not corrected:  # nothing corrected, nothing drawn but the references
        assert len(series) == 1
        return
    correction = series[1]
    assert correction.name == "correction" and not correction.points
    np.testing.assert_allclose(correction.y, 100 * drift.gain(correction.x * 60))
    # it passes through the smoothed references (a step: two levels), not each one's noise
    at_references = np.interp(series[0].x, correction.x, correction.y)
    np.testing.assert_allclose(at_references, 100 * drift.smoothed)
    assert np.ptp(at_references) == pytest.approx(
        100 * generated.display.drift[1] / (1 - generated.display.drift[1]), rel=0.1)


def test_without_times_the_white_references_are_drawn_against_row_order(tmp_path):
    from workbench.diagnostics import diagnose
    from workbench.measurement.ti3 import write_session_ti3
    from workbench.session_readers import read_session
    from workbench.simulated_sessions import simulate_session

    path = write_session_ti3(simulate_session({"temporal-drift": 0.05}, seed=1), tmp_path / "s.ti3")
    diagnosis = diagnose(read_session(path))
    assert diagnosis.context.time_basis == "row order"
    view = views.white_reference_view(diagnosis)
    assert view.x_label == "row (no times: row order)"
    np.testing.assert_allclose(view.series[0].x, diagnosis.context.drift.times)  # rows, not minutes
    # the HTML report draws them on the same axes
    from workbench.diagnostics.report import _drift_figure

    axis = _drift_figure(diagnosis).axes[0]
    assert (axis.get_xlabel(), axis.get_ylabel()) == (view.x_label, view.y_label)
    np.testing.assert_allclose(axis.lines[0].get_xdata(), view.series[0].x)
