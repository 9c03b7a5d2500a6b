"""The independent generator's added forms, pairs, plans and hidden truth do what they say.

Only the generator is checked here (fast, no diagnosis): how the diagnosis
fares on these forms is measured by ``tests/diagnostics/peer_bench.py``.
"""

import numpy as np
import pytest

from tests.diagnostics.independent_generator import (
    FORMS,
    NEW_FORMS,
    PAIRED_FORMS,
    SUITE_FORMS,
    TOE_BUMP,
    generate_session,
    hidden_colours,
    nearest_power_law_distance,
)
from tests.diagnostics.suite import suite_cases

SEEDS = range(4)
WHITE = np.array([[255.0, 255, 255]])
PRIMARIES = np.diag([255.0, 255, 255])


def _sweeps(level_step=5):
    levels = np.arange(level_step, 256, level_step, dtype=float)
    return np.vstack([np.outer(levels, np.eye(3)[c]) for c in range(3)])


def _greys(levels=np.arange(5, 256, 5, dtype=float)):
    return np.repeat(levels[:, None], 3, axis=1)


def test_forms_grow_and_the_suite_keeps_its_own():
    for effect, forms in SUITE_FORMS.items():
        assert FORMS[effect][:len(forms)] == forms
        assert set(FORMS[effect]) == set(forms) | set(NEW_FORMS.get(effect, ()))
    hidden = {(e, f) for _, effects, _ in suite_cases(0) for e, f in effects.items()}
    assert hidden == {(e, f) for e, forms in SUITE_FORMS.items() for f in forms}
    for name, effects in PAIRED_FORMS.items():
        assert all(form in FORMS[effect] for effect, form in effects.items()), name


def test_an_old_form_session_is_unchanged_by_the_additions():
    # the same seed with and without a new form: the display (drawn first) is the same, and
    # a session of an old form is drawn exactly as before the additions
    old = generate_session({"channel-interaction": "power-limit"}, seed=7)
    new = generate_session({"channel-interaction": "knee"}, seed=7)
    assert np.array_equal(old.effect_free_XYZ, new.effect_free_XYZ)
    again = generate_session({"channel-interaction": "power-limit"}, seed=7)
    assert np.array_equal(old.session.XYZ, again.session.XYZ)


@pytest.mark.parametrize("seed", SEEDS)
def test_drive_crosstalk_keeps_white_additive_and_the_sweeps_untouched(seed):
    generated = generate_session({"channel-interaction": "drive-crosstalk"}, seed=seed)
    share = generated.effects["channel-interaction"][1]
    assert 0.02 <= share <= 0.06
    display, free = generated.display, generated.effect_free_display
    white = display.light(WHITE)[0]
    added = display.light(PRIMARIES).sum(axis=0) - 2 * display.black
    assert np.max(np.abs(white - added) / white[1]) < 1e-3
    sweeps = _sweeps()
    assert np.array_equal(display.light(sweeps), free.light(sweeps))
    # greys and mixtures take their neighbours' share: brighter, by about the share, not more
    greys = _greys(np.array([64.0, 128.0, 192.0]))
    ratio = display.light(greys)[:, 1] / free.light(greys)[:, 1]
    assert np.all(ratio > 1) and np.all(ratio < (1 + share) ** 2.7)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_knee_loses_nothing_below_its_knee_and_its_amount_at_white(seed):
    generated = generate_session({"channel-interaction": "knee"}, seed=seed)
    display, free = generated.display, generated.effect_free_display
    form, loss, knee = display.interaction
    assert 0.05 <= loss <= 0.15 and 0.4 <= knee <= 0.6
    rgb = np.vstack([_greys(), _sweeps(), hidden_colours(200, seed)])
    load = display.linear(rgb / 255.0) @ display.shares
    ratio = display.light(rgb)[:, 1] / free.light(rgb)[:, 1]
    below = load < knee
    assert below.sum() > 50 and (~below).sum() > 20
    assert np.allclose(ratio[below], 1.0, atol=1e-12)
    assert np.all(ratio[~below] <= 1.0) and np.all(np.diff(ratio[:51]) <= 1e-12)  # the greys
    white_ratio = display.light(WHITE)[0, 1] / free.light(WHITE)[0, 1]
    assert white_ratio == pytest.approx(1 - loss, abs=1e-9)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_quadratic_power_limit_dims_by_the_load_squared(seed):
    generated = generate_session({"channel-interaction": "power-limit-quadratic"}, seed=seed)
    display, free = generated.display, generated.effect_free_display
    loss = display.interaction[1]
    assert 0.05 <= loss <= 0.15
    rgb = np.vstack([_greys(), _sweeps()])
    load = display.linear(rgb / 255.0) @ display.shares
    ratio = display.light(rgb)[:, 1] / free.light(rgb)[:, 1]
    assert np.allclose(ratio, 1 - loss * load ** 2, atol=1e-12)
    white_ratio = display.light(WHITE)[0, 1] / free.light(WHITE)[0, 1]
    assert white_ratio == pytest.approx(1 - loss, abs=1e-9)


@pytest.mark.parametrize("form", NEW_FORMS["tone-curve-shape"])
@pytest.mark.parametrize("seed", SEEDS)
def test_the_new_tone_shapes_are_monotone_and_15_to_60_thousandths_from_a_power_law(form, seed):
    generated = generate_session({"tone-curve-shape": form}, seed=seed)
    display = generated.display
    codes = np.arange(256) / 255.0
    output = display.linear(np.repeat(codes[:, None], 3, axis=1))
    assert np.all(np.diff(output, axis=0) >= 0)
    assert np.allclose(output[0], 0.0) and np.allclose(output[-1], 1.0)
    distance = max(nearest_power_law_distance(output[:, c]) for c in range(3))
    assert 0.015 - 1e-4 <= distance <= 0.06 + 1e-4
    assert distance == pytest.approx(generated.effects["tone-curve-shape"][1], abs=1e-4)
    # independently: a dense grid of exponents finds no power law closer
    gammas = np.arange(0.5, 5.0, 0.001)
    dense = max(np.min(np.max(np.abs(output[:, c][None] - codes[None] ** gammas[:, None]), axis=1))
                for c in range(3))
    assert dense == pytest.approx(distance, rel=0.02)
    if form == "toe":
        # crushed near black (nothing below the threshold), lifted in the shadows
        lifted = output - codes[:, None] ** display.gammas
        assert np.all(output[:8] == 0.0)
        assert np.all(lifted[int(TOE_BUMP * 255)] > 0)
    else:
        # a soft shoulder: the light at mid drive rises above the channel's power law
        lifted = output - codes[:, None] ** display.gammas
        assert np.all(lifted[128] > 0) and np.all(lifted[1:-1] >= 0)


@pytest.mark.parametrize("plan", ["paper", "paper+greys", "authors-2024"])
def test_every_plan_is_measured_on_the_same_display(plan):
    generated = generate_session({"channel-interaction": "knee"}, seed=5, plan=plan)
    paper = generate_session({"channel-interaction": "knee"}, seed=5, plan="paper")
    assert generated.plan == plan
    assert generated.display.interaction == paper.display.interaction
    assert np.array_equal(generated.display.columns, paper.display.columns)
    session = generated.session
    assert len(session) == len(generated.true_XYZ)
    if plan != "paper":
        greys = session.rgb[session.mask("grey")]
        assert len(greys) >= 15 and np.all(greys[:, 0] == greys[:, 2])


@pytest.mark.parametrize("name", list(PAIRED_FORMS))
def test_paired_forms_hide_both_effects(name):
    generated = generate_session(name, seed=3, plan="authors-2024")
    assert {e: f for e, (f, _) in generated.effects.items()} == PAIRED_FORMS[name]
    assert generated.session.metadata["effects"] == PAIRED_FORMS[name]


@pytest.mark.parametrize("effects", [{"temporal-drift": "step"}, {"tone-curve-shape": "toe"},
                                     {"channel-interaction": "drive-crosstalk"}])
def test_the_truth_is_known_for_any_colour(effects):
    generated = generate_session(effects, seed=11, plan="paper+greys")
    session = generated.session
    # at the rows' times it is the session's noiseless truth
    assert np.allclose(generated.true_at(session.rgb, session.t_s), generated.true_XYZ,
                       rtol=1e-12, atol=1e-12)
    hidden = hidden_colours(300, seed=11)
    assert hidden.shape == (300, 3) and not np.array_equal(hidden, hidden_colours(300, 12))
    reference = generated.reference_XYZ(hidden)
    whites = np.flatnonzero(session.mask("white"))[-2:]
    at_whites = generated.true_XYZ[whites].mean(axis=0)
    assert np.allclose(generated.reference_XYZ(WHITE)[0], at_whites, rtol=1e-12)
    if "temporal-drift" in effects:
        assert generated.reference_gain != 1.0
        early = generated.true_at(hidden, np.zeros(300))
        assert not np.allclose(early, reference, rtol=1e-3)
    else:
        assert generated.reference_gain == 1.0
        assert np.allclose(generated.true_at(hidden), reference)


def test_the_peer_bench_counts_its_rates_without_a_diagnosis():
    from tests.diagnostics.peer_bench import PeerOutcome, scenarios, summarize, table

    assert {"clean", "channel-interaction/drive-crosstalk", "tone-curve-shape/toe"} <= set(
        scenarios()) and set(PAIRED_FORMS) <= set(scenarios())

    def outcome(seed, findings, ours, authors):
        return PeerOutcome(plan="authors-2024", scenario="knee", seed=seed,
                           effects={"channel-interaction": "knee"}, magnitudes={}, noise=0.001,
                           findings=findings, ours_dE00=ours, baseline_dE00=1.0,
                           authors_dE00=authors)

    outcomes = [outcome(1, ("channel-interaction", "tone-curve-shape"), 0.30, 0.70),
                outcome(2, ("tone-curve-shape", "channel-interaction"), 0.50, 0.45),
                outcome(3, ("unexplained-residual",), 0.20, 0.20)]
    row, = summarize(outcomes)
    assert row["n"] == 3 and row["ours_dE00"] == pytest.approx(1.0 / 3)
    assert row["ours_worse"] == pytest.approx(1 / 3)  # 0.50 > 0.45 + 0.01; 0.20 is a tie
    assert row["all_named"] == pytest.approx(2 / 3) and row["first_injected"] == pytest.approx(1 / 3)
    assert row["false_sessions"] == pytest.approx(2 / 3) and row["unexplained"] == 1
    assert "seed 2" in table(outcomes)
