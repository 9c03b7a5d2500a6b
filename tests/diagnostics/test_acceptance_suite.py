"""The issue's acceptance, measured on sessions of the independent generator (not our simulator).

The seeded suite (94 sessions: clean ones, every form of every effect,
pairs on the paper plan; clean ones, every interaction form and three pairs on
``paper+greys``; noise 0.05–0.5 %), pooled over :data:`SUITE_SEEDS` seeds
(940 sessions, so a rate near its 5 % goal is known to ±0.7 points), is
``slow``; ``python -m workbench bench diagnose-suite`` prints the same rates. The quick tests check the generator
itself and one session per effect.
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import SUITE_FORMS, generate_session
from tests.diagnostics.suite import SUITE_SEEDS, pooled_cases, run_suite, suite_cases
from workbench.diagnostics import MATERIALITY_FLOOR_DE00, diagnose
from workbench.diagnostics.extension import CROSSTALK_EXPONENT


def test_the_generator_shares_no_form_with_the_simulated_headset_or_the_extension():
    import tests.diagnostics.independent_generator as generator

    source = open(generator.__file__).read()
    assert "from instruments" not in source and "import instruments" not in source
    assert "workbench.display" not in source and "workbench.diagnostics" not in source


def test_a_clean_generated_session_is_the_papers_model_plus_noise():
    generated = generate_session({}, seed=3, noise=0.001)
    diagnosis = diagnose(generated.session)
    assert diagnosis.findings == ()
    assert diagnosis.extended is diagnosis.baseline
    assert diagnosis.baseline_score.mean_dE00 < 0.3
    # the noise model recovers the generator's repeatability within a factor of 1.5
    estimated = diagnosis.context.noise.relative_sd_at(1.0)
    assert 0.001 / 1.5 < estimated < 0.0011 * 1.5


@pytest.mark.parametrize("effect, form", [("black-offset", "bluish"),
                                          ("tone-curve-shape", "shoulder"),
                                          ("temporal-drift", "step"),
                                          ("chromaticity-shift", "leak")])
def test_one_hidden_form_per_effect_is_named_without_false_causes(effect, form):
    generated = generate_session({effect: form}, seed=41)
    diagnosis = diagnose(generated.session)
    named = {f.effect for f in diagnosis.findings} - {"unexplained-residual"}
    # the stated consequence: a step between two white references is corrected by a ramp
    # between them, so a sweep measured across it may show a (material) shape
    consequences = {"temporal-drift": {"tone-curve-shape"}}.get(effect, set())
    assert effect in named and named - {effect} <= consequences
    assert diagnosis.findings[0].effect == effect
    finding = next(f for f in diagnosis.findings if f.effect == effect)
    assert finding.z > finding.critical_z and finding.impact_dE00 >= MATERIALITY_FLOOR_DE00
    assert np.isfinite(finding.standard_error) and finding.standard_error > 0
    if effect == "temporal-drift":
        # the step is named as such; the validation colours (measured last) may all lie after
        # it, so the held-out gain can be nil, but the extension never loses
        assert "a step" in finding.evidence
        assert diagnosis.gain_pct >= 0
    else:
        assert diagnosis.gain_pct >= 30


def test_the_suite_covers_every_form_and_at_least_60_sessions():
    cases = suite_cases()
    assert len(cases) >= 60
    hidden = {(e, f) for _, effects, _ in cases for e, f in effects.items()}
    # (the forms it was fixed with; forms added since are measured by peer_bench)
    assert hidden == {(e, f) for e, forms in SUITE_FORMS.items() for f in forms}
    assert sum(not effects for _, effects, _ in cases) >= 20
    assert any(len(effects) == 2 for _, effects, _ in cases)
    # interactions are also measured where the plan can identify their shape, clean ones too
    greys = [effects for _, effects, plan in cases if plan == "paper+greys"]
    assert {effects.get("channel-interaction") for effects in greys} >= set(
        SUITE_FORMS["channel-interaction"])
    assert sum(not effects for effects in greys) >= 5


def test_an_interaction_measured_with_greys_is_modelled_for_a_gain():
    generated = generate_session({"channel-interaction": "crosstalk"}, seed=703,
                                 plan="paper+greys")
    assert generated.session.mask("grey").sum() == 15
    diagnosis = diagnose(generated.session)
    # (this session's first white reference reads 3.9 σ low, and the drift test's smooth trend
    # names it: one of the suite's stated false findings, 1.7 % of clean sessions)
    finding = next(f for f in diagnosis.findings if f.effect == "channel-interaction")
    assert finding.in_model
    assert "unexplained-residual" not in {f.effect for f in diagnosis.findings}
    term = next(t for t in diagnosis.to_json()["extended"]["terms"]
                if t["effect"] == "channel-interaction")
    assert "greys" in term["fitted_on"] and "not identified" not in term["fitted_on"]
    assert diagnosis.gain_pct >= 50


def test_a_common_gain_interaction_on_the_paper_plan_is_named_unexplained_and_costs_nothing():
    # a backlight scales every channel alike: the white says how much, nothing says the shape
    generated = generate_session({"channel-interaction": "backlight"}, seed=703)
    diagnosis = diagnose(generated.session)
    named = [f.effect for f in diagnosis.findings]
    assert named == ["channel-interaction", "unexplained-residual"]
    assert "as one gain on every channel" in diagnosis.findings[0].evidence
    assert "greys" in diagnosis.unexplained.evidence
    term = diagnosis.to_json()["extended"]["terms"][0]
    assert "not identified" in term["fitted_on"]
    # the most conservative shape: white is fixed, partial-drive mixtures stay additive
    assert abs(diagnosis.gain_pct) < 5


def test_a_channel_specific_interaction_on_the_paper_plan_takes_the_crosstalk_shape():
    # crosstalk couples each channel by its own amount: the white's chromaticity moves, which
    # no common gain does, and the drive-linear shape of subpixel coupling is taken
    generated = generate_session({"channel-interaction": "crosstalk"}, seed=703)
    diagnosis = diagnose(generated.session)
    finding = next(f for f in diagnosis.findings if f.effect == "channel-interaction")
    assert "channel by channel" in finding.evidence and finding.in_model
    assert finding.details["channel_specific"]
    term = next(t for t in diagnosis.to_json()["extended"]["terms"]
                if t["effect"] == "channel-interaction")
    assert "crosstalk" in term["fitted_on"]
    assert diagnosis.extended.interaction.exponent == CROSSTALK_EXPONENT
    assert "unexplained-residual" not in {f.effect for f in diagnosis.findings}
    assert diagnosis.gain_pct >= 50


def test_a_crosstalk_fitted_on_greys_meets_the_white_its_eleven_references_measure():
    # with greys the co-drive amounts are a least-squares fit over the greys and the white; the
    # white is the mean of eleven references on paper+greys, and weighed as one grey the term
    # missed it by up to 1.3 ΔE00 on these displays (an adaptive session's extension then lost
    # the choice on its held-out whites)
    from workbench.colorimetry import delta_E2000
    from workbench.diagnostics.detectors import build_context
    from workbench.diagnostics.extension import fit_extended

    misses = []
    for seed in range(6):
        session = generate_session({"channel-interaction": "crosstalk"}, seed=seed,
                                   plan="paper+greys").session.without("validation")
        context = build_context(session)
        assert context.white_count == 11
        model = fit_extended(context, ["channel-interaction"])
        assert model.interaction is not None and model.interaction.amounts is not None
        misses.append(float(delta_E2000(model.forward(np.full((1, 3), 255.0)),
                                        context.white[None], context.white)[0]))
    assert max(misses) < 0.6, misses


def test_a_significant_chromaticity_shift_that_does_not_beat_noise_stays_out_of_the_model():
    # log-desaturation at 0.1 % noise: the dark sweep points' xy move (z ≫ critical), but the
    # term predicts unseen fit rows no better than noise allows; the baseline is kept
    diagnosis = diagnose(generate_session({"chromaticity-shift": "log-desaturation"},
                                          seed=118).session)
    finding = diagnosis.findings[0]
    assert finding.effect == "chromaticity-shift" and finding.z > 3 * finding.critical_z
    assert not finding.in_model and "beyond noise" in finding.cross_validation
    assert diagnosis.extended_score.mean_dE00 <= diagnosis.baseline_score.mean_dE00


def test_the_drift_correction_is_smoothed_to_the_references_noise():
    from workbench.diagnostics.evidence import DriftCorrection

    times = np.arange(10.0)
    jitter = np.array([1, -1, 1, -1, 1, -1, 1, -1, 1, -1]) * 0.004
    trend = 0.95 + 0.005 * times
    drift = DriftCorrection(times, trend + jitter, trend + jitter)
    smoothed = drift.smoothed_to_noise(np.full(10, 0.005))
    # both relative to the settled reference state (evidence.settled_reference): compare shapes
    scale = drift.gains[-1] / smoothed.gains[-1]
    # ±σ jitter is averaged out, the trend (10 σ over the session) is kept
    assert np.max(np.abs(smoothed.gain(times) * scale - trend)) < 0.5 * np.max(np.abs(jitter))
    # the references are kept as measured, on the new reference state
    np.testing.assert_allclose(smoothed.gains * scale, drift.gains, rtol=1e-12)
    step = np.where(times < 5, 1.0, 0.95)
    sharp = DriftCorrection(times, step, step).smoothed_to_noise(np.full(10, 0.002))
    assert np.max(np.abs(sharp.gain(times) * step[-1] / sharp.gains[-1] - step)) < 0.004
    # the settled state after the step is the reference: the rows measured there need no correction
    assert sharp.gain(times[-5:]) == pytest.approx(1.0)


def test_the_drift_corrections_uncertainty_is_half_a_change_midway_and_nil_at_references():
    from workbench.diagnostics.evidence import DriftCorrection

    times = np.array([0.0, 10.0, 20.0, 30.0])
    gains = np.array([0.96, 1.0, 1.0, 1.0])  # a warm-up the second reference already missed
    drift = DriftCorrection(times, gains, gains)
    u = drift.uncertainty(np.array([-5.0, 0.0, 2.5, 5.0, 10.0, 15.0, 35.0]))
    change = 0.04 / 0.98
    assert u[[0, 1, 4, 5, 6]] == pytest.approx(0.0)  # outside, at references, references agree
    assert u[3] == pytest.approx(change / 2)  # midway: the change happened before or after
    assert u[2] == pytest.approx(change * np.sqrt(0.25 * 0.75))


def test_a_sweep_measured_across_a_drift_step_carries_the_corrections_uncertainty():
    from workbench.diagnostics.detectors import build_context

    generated = generate_session({"temporal-drift": "step"}, seed=41)
    context = build_context(generated.session.without("validation"))
    assert context.drift_found
    uncertain = [s.correction_sd for s in context.sweeps]
    assert all(u is not None for u in uncertain)
    # the sweep measured while the display stepped carries up to half the step; the others none
    step = float(np.ptp(context.drift.gain(generated.session.t_s)))
    largest = max(float(u.max()) for u in uncertain)
    assert 0.3 * step < largest <= 0.5 * step + 1e-9
    assert min(float(np.median(u)) for u in uncertain) < 1e-3


@pytest.mark.slow
def test_acceptance_rates_on_the_seeded_suite():
    result = run_suite(cases=pooled_cases(SUITE_SEEDS))
    print(result.summary())
    assert result.sessions == 94 * SUITE_SEEDS
    assert result.clean_rate <= 0.05
    assert result.false_rate <= 0.05
    assert all(result.named_rate(effect) >= 0.95 for effect in result.effect_sessions)
    # every miss is below noise or below the materiality floor, and says so with its figures
    assert all("below noise" in miss or "below the materiality floor" in miss
               for miss in result.misses())
    assert np.median(result.gains_pct) >= 30
    assert result.clean_losses == 0
    # where the plan can identify the effect and the effect reaches the held-out colours
    rows = {(r["plan"], r["sessions"]): r for r in result.gain_table()}
    greys = rows[("paper+greys", "effect touches the held-out colours")]
    # (90 of 91 at the last measurement; the one short, a power limit whose effect on the
    # held-out colours is 1.2 times the noise's share, gains 6 %)
    assert greys["n"] >= 80 and greys["gain_at_least_30pct"] >= 0.95
