"""Full-drive primaries estimated with the white references as well, where the white is their sum.

On an additive display the white less the black is the sum of the full-drive primaries, and the
white references, read many times, say what each primary's one or two readings cannot. The
extension moves each primary by the generalized least-squares step
(:func:`~workbench.diagnostics.extension.white_constrained`) wherever it has no interaction term
(whose evidence is the white's shortfall), whatever the additivity test says; beside flexible
tone curves by a gain alone. The diagnosis decides its terms and its model without the step and
exports the extension with it.

The sessions come from the independent generator (its own noise: a t-distributed gain, a
per-coordinate part, shot noise and a dark floor); the truth is its noiseless display.
"""

import html

import numpy as np
import pytest

from tests.diagnostics.independent_generator import generate_session, hidden_colours
from tests.diagnostics.peer_bench import hidden_score
from workbench.colorimetry import delta_E2000
from workbench.diagnostics import diagnose
from workbench.diagnostics.authors import fit_grey_ramp_linearisation
from workbench.diagnostics.detectors import additivity_p_value, build_context
from workbench.diagnostics.extension import constrained_by_whites, fit_extended, white_constrained
from workbench.diagnostics.model_choice import PRIMARIES_AS_MEASURED
from workbench.diagnostics.report import render_report
from workbench.gui.diagnosis_views import model_choice_reason

SEEDS = range(8)
RGB = np.array([[10.0, 120.0, 250.0], [200.0, 30.0, 90.0], [255.0, 255.0, 255.0]])


def _context(effects, seed, noise=0.004):
    generated = generate_session(effects, seed=seed, noise=noise)
    return generated, build_context(generated.session.without("validation"))


def _primary_errors(generated, context):
    """Each channel's full-drive XYZ less the black, against the true display's (relative)."""
    true = generated.display.light(np.array([[255.0, 0, 0], [0, 255.0, 0], [0, 0, 255.0],
                                             [0, 0, 0]]))
    truth = true[:3] - true[3]
    measured = np.array([s.full_XYZ for s in context.sweeps])
    return np.abs(measured - truth) / truth[:, 1:2]


@pytest.fixture(scope="module")
def clean():
    return [_context(None, seed) for seed in SEEDS]


def test_the_whites_bring_the_primaries_closer_to_the_truth(clean):
    before, after = [], []
    for generated, context in clean:
        assert constrained_by_whites(context, ())
        moved = white_constrained(context)
        before.append(_primary_errors(generated, context).mean())
        after.append(_primary_errors(generated, moved).mean())
    assert np.mean(after) < 0.8 * np.mean(before), (before, after)


def test_the_extension_predicts_hidden_colours_better_with_the_whites(clean):
    rgb = hidden_colours(300, 1)
    plain, constrained = [], []
    for generated, context in clean:
        truth = generated.display.light(rgb)
        white = generated.display.light(np.array([[255.0, 255.0, 255.0]]))[0]
        constrained.append(delta_E2000(fit_extended(context, (), with_whites=True).forward(rgb), truth,
                                       white).mean())
        plain.append(delta_E2000(fit_extended(context, ()).forward(rgb),
                                 truth, white).mean())
    assert np.mean(constrained) < 0.9 * np.mean(plain), (plain, constrained)


def test_an_interaction_term_moves_nothing():
    clean_context = _context(None, 0)[1]
    assert white_constrained(clean_context) is not None
    assert not constrained_by_whites(clean_context, ("channel-interaction",))
    np.testing.assert_allclose(
        fit_extended(clean_context, ("channel-interaction",), with_whites=True).forward(RGB),
        fit_extended(clean_context, ("channel-interaction",)).forward(RGB))


def test_a_white_off_the_sum_beyond_noise_moves_the_primaries_of_a_model_with_no_interaction_term():
    """A panel that dims its white (a power limit) fails the additivity test; a model without the
    interaction's term predicts the white as the primaries' sum all the same, and the step
    shares the shortfall among them: the white then comes out near its reading."""
    _, context = _context({"channel-interaction": "power-limit"}, seed=3, noise=0.002)
    assert additivity_p_value(context) < 1e-6
    assert constrained_by_whites(context, ())
    white = np.array([[255.0, 255.0, 255.0]])
    as_read = fit_extended(context, ()).forward(white)[0]
    moved = fit_extended(context, (), with_whites=True).forward(white)[0]
    measured = context.white
    assert np.abs(moved - measured).max() < 0.2 * np.abs(as_read - measured).max()


@pytest.mark.parametrize("effects, seed", [
    ({"temporal-drift": "decline"}, 0),  # corrected: the drift curve's noise at each primary
    (None, 2),  # clean, its whites scattering beyond noise: the change no correction took out
])
def test_each_primary_takes_the_share_of_the_departure_the_test_gave_it(effects, seed):
    """The step is ``P_c + C_c V⁻¹ d`` with ``V`` the additivity test's covariance: each primary's
    ``C_c`` must be its own part of ``V``, what the drift adds to it included, so the departure
    the primaries leave is the white's and the black's share of it alone."""
    from workbench.diagnostics.detectors import (curve_variance, mean_covariance,
                                                 unexplained_gain_variance, white_against_sum)

    _, context = _context(effects, seed=seed)
    assert constrained_by_whites(context, ())
    drifting = unexplained_gain_variance(context)
    if context.drift_found:
        assert all(curve_variance(context, s.times[-1:], 1)[0] > 1e-6 for s in context.sweeps)
    else:
        assert drifting > 1e-6
    white, summed, covariance, _ = white_against_sum(context)
    moved = white_constrained(context)
    left = white - sum(s.full_XYZ for s in moved.sweeps)
    noise = context.noise
    others = (mean_covariance(noise, context.white, context.white_count)
              + 4 * mean_covariance(noise, context.black, context.black_count)
              + drifting * np.outer(context.white, context.white) / context.white_count)
    expected = others @ np.linalg.solve(covariance, white - summed)
    np.testing.assert_allclose(left, expected, rtol=1e-9, atol=1e-12 * np.abs(white).max())
    assert np.abs(white - summed).max() > 3 * np.abs(expected).max()  # the step did its work


def test_beside_flexible_tone_curves_each_primary_moves_by_a_gain_alone():
    """A flexible tone curve is a table through its sweep relative to the full-drive point: the
    primaries move along themselves (their chromaticity as read), and the exported model is
    the one fitted so."""
    context = _context(None, 0)[1]
    assert constrained_by_whites(context, ("tone-curve-shape",))
    full, gained = white_constrained(context), white_constrained(context, gain_only=True)
    for sweep, moved, along in zip(context.sweeps, full.sweeps, gained.sweeps):
        np.testing.assert_allclose(along.full_xy, sweep.full_xy, atol=1e-12)
        assert abs(along.full_XYZ[1] / sweep.full_XYZ[1] - 1) > 1e-6  # it did move
        assert np.abs(moved.full_xy - sweep.full_xy).max() > 1e-6  # the whole step moves xy
    forms = ("spline",) * 3
    np.testing.assert_allclose(
        fit_extended(context, ("tone-curve-shape",), tone_forms=forms,
                     with_whites=True).forward(RGB),
        fit_extended(gained, ("tone-curve-shape",), tone_forms=forms).forward(RGB))


def test_a_gain_alone_helps_flexible_tone_curves():
    """On the paper plan's shoulders and soft toes (seeds 0–15 each) each primary moved by its
    gain alone predicts hidden colours better than the primaries as read, and seldom worse."""
    rgb = hidden_colours(300, 2)
    read, gained = [], []
    for form in ("shoulder", "soft-toe"):
        for seed in range(16):
            generated, context = _context({"tone-curve-shape": form}, seed)
            moved = white_constrained(context, gain_only=True)
            if moved is None:  # the additivity test refuses the step
                continue
            truth = generated.display.light(rgb)
            white = generated.display.light(np.array([[255.0, 255.0, 255.0]]))[0]
            forms = [c.form for c in fit_extended(context, ("tone-curve-shape",)).tone]
            for scores, used in ((read, context), (gained, moved)):
                model = fit_extended(used, ("tone-curve-shape",), tone_forms=forms)
                scores.append(delta_E2000(model.forward(rgb), truth, white).mean())
    read, gained = np.array(read), np.array(gained)
    assert read.size >= 24, read.size
    assert gained.mean() < read.mean(), (read.mean(), gained.mean())
    assert np.sum(gained > read + 0.01) <= 2, np.round(np.c_[read, gained], 3)


def test_the_diagnosis_exports_the_step_and_says_so():
    """Term selection and the model choice decide without the step; the exported extension
    has it, and the JSON, the CLI's text and the report say how its primaries were estimated."""
    generated = generate_session("bluish + log-desaturation", seed=0, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    assert diagnosis.model_choice.chosen == "extension"
    terms = [r.effect for r in diagnosis.findings if r.in_model]
    assert constrained_by_whites(diagnosis.context, terms)
    np.testing.assert_allclose(
        diagnosis.extended.forward(RGB),
        fit_extended(diagnosis.context, terms, diagnosis.baseline,
                     [c.form for c in diagnosis.extended.tone], with_whites=True).forward(RGB))
    rgb = hidden_colours(300, 0)
    truth = generated.display.light(rgb)
    unmoved = fit_extended(diagnosis.context, terms, diagnosis.baseline,
                           [c.form for c in diagnosis.extended.tone])
    exported = delta_E2000(diagnosis.extended.forward(rgb), truth, diagnosis.white).mean()
    without = delta_E2000(unmoved.forward(rgb), truth, diagnosis.white).mean()
    assert exported < without, (exported, without)
    primaries = diagnosis.to_json()["model_choice"]["primaries"]
    assert primaries.startswith("estimated with the 11 white references as well"), primaries
    assert "additivity test p" in primaries
    assert html.escape(f"Full-drive primaries {primaries}") in render_report(diagnosis)
    assert primaries in model_choice_reason(diagnosis)


def test_a_model_other_than_the_extension_keeps_its_primaries_as_measured():
    generated = generate_session({"tone-curve-shape": "shoulder"}, seed=0, plan="paper+greys")
    diagnosis = diagnose(generated.session)
    assert diagnosis.model_choice.chosen != "extension"
    assert diagnosis.to_json()["model_choice"]["primaries"] == PRIMARIES_AS_MEASURED
    assert model_choice_reason(diagnosis) == diagnosis.model_choice.reason


def test_a_soft_shoulder_whose_green_primary_read_bright_keeps_up_with_the_authors_method():
    """The peer bench's one session behind the seed authors' method: a soft shoulder on
    ``paper+greys`` (seed 46003) whose green primary was read 0.9 % bright in X, Y and Z, and
    whose grey ramp puts the white, eleven readings, at the top of its ramp. With its primaries as
    read the exported extension scored 0.153 mean ΔE00 on hidden colours against the authors'
    0.138; moved by their gains it scores 0.114."""
    generated = generate_session({"tone-curve-shape": "shoulder-soft"}, seed=46003,
                                 plan="paper+greys")
    diagnosis = diagnose(generated.session)
    assert [f.effect for f in diagnosis.findings] == ["tone-curve-shape"]
    assert diagnosis.model_choice.chosen == "extension"
    primaries = diagnosis.to_json()["model_choice"]["primaries"]
    assert primaries.endswith("by a gain alone beside flexible tone curves"), primaries
    ours = hidden_score(generated, diagnosis.extended, diagnosis.white, 46003)
    authors = hidden_score(generated, fit_grey_ramp_linearisation(generated.session),
                           diagnosis.white, 46003)
    assert ours <= authors + 0.01, (ours, authors)


def test_primaries_read_low_are_moved_where_the_additivity_test_finds_the_departure():
    """Peer seed 69008, a warm-up on the seed authors' plan: its green and blue primaries read
    0.2 % and 0.3 % low (the instrument's noise) and its red one, measured during the warm-up,
    was corrected 0.4 % low by a white reference read high, while the white was read twelve
    times. The additivity test's p is below 0.05, where the step had been refused: the exported
    extension then scored 0.069 mean ΔE00 on hidden colours against the authors' method's
    0.050; with the step 0.038, and the diagnosis says why it took it."""
    seed = 69008
    generated = generate_session({"temporal-drift": "warm-up"}, seed=seed, plan="authors-2024")
    diagnosis = diagnose(generated.session)
    assert [f.effect for f in diagnosis.findings] == ["temporal-drift"]
    assert diagnosis.model_choice.chosen == "extension"
    assert additivity_p_value(diagnosis.context) < 0.05
    primaries = diagnosis.to_json()["model_choice"]["primaries"]
    assert primaries.startswith("estimated with the 12 white references as well: the model has "
                                "no interaction term"), primaries
    assert "the departure is beyond noise" in primaries
    ours = hidden_score(generated, diagnosis.extended, diagnosis.white, seed)
    authors = hidden_score(generated, fit_grey_ramp_linearisation(generated.session),
                           diagnosis.white, seed)
    assert ours <= authors + 0.01, (ours, authors)
