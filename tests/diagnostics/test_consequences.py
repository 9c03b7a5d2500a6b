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
