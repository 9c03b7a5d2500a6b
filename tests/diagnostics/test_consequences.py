"""A finding another finding explains is reported after it, as its consequence.

A power limit (the panel dims the whole frame as its load grows) bends the
bright channels' sweeps, so the tone-curve test fires beside the interaction
test: one cause, two findings. The data come from the independent generator
(its own load definition, its own noise); the workbench fits a load gain of
its own form (:mod:`workbench.diagnostics.power_limit`).
"""

from __future__ import annotations

import pytest

from tests.diagnostics.independent_generator import generate_session
from workbench.diagnostics import diagnose
from workbench.diagnostics.power_limit import tone_bend_explained

SEEDS = range(200, 206)


@pytest.mark.parametrize("form", ["power-limit-quadratic", "knee"])
def test_a_power_limit_is_the_cause_and_the_tone_bend_its_consequence(form):
    outcomes = []
    for seed in SEEDS:
        diagnosis = diagnose(generate_session({"channel-interaction": form}, seed=seed).session)
        findings = [f for f in diagnosis.findings if f.effect != "unexplained-residual"]
        effects = [f.effect for f in findings]
        assert effects[0] == "channel-interaction", (seed, effects)  # the cause first
        tone = next((f for f in findings if f.effect == "tone-curve-shape"), None)
        if tone is not None:
            outcomes.append(tone.details.get("consequence_of") == "channel-interaction")
            document = diagnosis.to_json()
            listed = {f["effect"]: f for f in document["findings"]}
            assert listed["tone-curve-shape"]["consequence_of"] == (
                "channel-interaction" if outcomes[-1] else None)
            if outcomes[-1]:
                assert "power limit" in tone.evidence
        # the model of the cause predicts the colours the fit never saw better than the paper's
        assert diagnosis.extended_score.mean_dE00 < diagnosis.baseline_score.mean_dE00
    assert outcomes and sum(outcomes) >= len(outcomes) - 1


@pytest.mark.parametrize("effects", [{"tone-curve-shape": "shoulder"},
                                     {"tone-curve-shape": "shoulder-soft"},
                                     {"channel-interaction": "crosstalk"},
                                     {"channel-interaction": "backlight"}, {}])
def test_no_power_limit_is_read_where_there_is_none(effects):
    for seed in SEEDS:
        diagnosis = diagnose(generate_session(effects, seed=seed).session)
        assert not tone_bend_explained(diagnosis.context)[0], (effects, seed)
        assert not any(f.details.get("consequence_of") for f in diagnosis.findings)
        assert diagnosis.model_choice.chosen != "power-limit"


@pytest.mark.parametrize("plan, form, seed", [("authors-2024", "power-limit-quadratic", 64002),
                                              ("paper", "knee", 63007)])
def test_a_power_limit_whose_white_is_short_channel_by_channel_is_still_the_cause(plan, form, seed):
    """Each primary is dimmed at its own load, so a power limit's white against R+G+B need not be
    one gain in X, Y and Z (the common-gain test calls it channel-specific here); one load gain
    that explains the sweeps' bend and the white together still names the power limit as the
    cause of the bend (peer sessions where the extension had been exported with a
    `tone-curve-shape` beside the interaction: 0.336 → 0.030 and 0.340 → 0.034 ΔE00 on hidden
    colours)."""
    diagnosis = diagnose(generate_session({"channel-interaction": form}, seed=seed, plan=plan).session)
    interaction = next(r for r in diagnosis.results if r.effect == "channel-interaction")
    assert interaction.found and interaction.details["channel_specific"]
    assert interaction.details["power_limit_explains"]  # its evidence read again with the sweeps
    assert interaction.evidence.endswith("a power limit, which dims each primary at its own load, "
                                         "not subpixel crosstalk")
    assert tone_bend_explained(diagnosis.context)[0]
    tone = next(f for f in diagnosis.findings if f.effect == "tone-curve-shape")
    assert tone.details.get("consequence_of") == "channel-interaction"
    assert diagnosis.model_choice.chosen == "power-limit"
