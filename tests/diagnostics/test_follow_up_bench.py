"""The follow-up bench's mechanics (fast; no rate is asserted: the bench measures the rates).

``python -m tests.diagnostics.follow_up_bench --seeds 10`` measures the acceptance
criterion; here two sessions of one form go through it, and the generator's follow-up
(:meth:`GeneratedSession.measure_more`) is checked to measure on the same display.
"""

import json
import math
from dataclasses import asdict

import numpy as np
import pytest

from tests.diagnostics.follow_up_bench import (
    BUDGET,
    FOLLOW_UP_SEED,
    FollowUpOutcome,
    run_follow_up_bench,
    session_outcome,
    summarize,
    table,
)
from tests.diagnostics.independent_generator import generate_session, patch_seconds
from workbench.measurement.plans import Patch

FORM = "knee"
SEEDS = (30000, 30001)


@pytest.fixture(scope="module")
def kept():
    out = []
    for seed in SEEDS:
        store: dict = {}
        outcome = session_outcome(FORM, seed, strict=True, keep=store)
        out.append((outcome, store))
    return out


def test_the_combined_session_is_the_session_then_the_follow_up(kept):
    for outcome, store in kept:
        session = store["generated"].session
        combined = store["combined"].session
        patches = store["follow_up"].patches
        assert patches, "a knee on the paper plan leaves the interaction's shape to identify"
        n = len(session)
        assert len(combined) == n + len(patches) == outcome.combined_rows
        # the session's rows unchanged, the follow-up's after them with their own kinds
        assert np.array_equal(combined.XYZ[:n], session.XYZ)
        assert np.array_equal(combined.rgb[:n], session.rgb)
        assert list(combined.kind[n:]) == [p.kind for p in patches]
        assert np.array_equal(combined.rgb[n:], np.array([p.rgb for p in patches], dtype=float))
        assert not combined.mask("validation")[n:].any()
        # the clock goes on at the generator's own time per patch
        added = np.diff(np.concatenate([[session.t_s[-1]], combined.t_s[n:]]))
        assert np.allclose(added, patch_seconds(store["generated"].display, combined.rgb[n:]))
        assert combined.t_s[n] > session.t_s[-1]
        # the same display: the new rows scatter about its truth by the session's noise
        truth = store["combined"].true_XYZ[n:]
        assert np.allclose(truth, store["generated"].true_at(combined.rgb[n:], combined.t_s[n:]))
        relative = combined.XYZ[n:, 1] / truth[:, 1] - 1
        assert np.max(np.abs(relative)) < 20 * outcome.noise + 0.01
        assert combined.metadata["follow_ups"][-1]["rows"] == len(patches)
        assert combined.metadata["follow_ups"][-1]["seed"] == FOLLOW_UP_SEED


def test_the_follow_up_is_within_its_budget_and_the_fields_are_finite(kept):
    for outcome, _ in kept:
        assert isinstance(outcome, FollowUpOutcome) and not outcome.error
        assert 0 < outcome.share <= BUDGET
        assert outcome.share_estimated is not None and 0 < outcome.share_estimated <= BUDGET + 1e-9
        for name in ("session_s", "follow_up_s", "validation_baseline_before",
                     "validation_exported_before", "validation_baseline_after",
                     "validation_exported_after", "hidden_baseline_before", "hidden_exported_before",
                     "hidden_baseline_after", "hidden_exported_after"):
            assert math.isfinite(getattr(outcome, name)), name
        for gain in (outcome.validation_gain_before, outcome.validation_gain_after,
                     outcome.hidden_gain_before, outcome.hidden_gain_after):
            assert math.isfinite(gain) and gain < 1
        assert outcome.findings_before and outcome.findings_after
        assert outcome.model_before and outcome.model_after
        assert sum(outcome.follow_up_kinds.values()) == outcome.follow_up_rows


def test_the_bench_runs_and_tabulates(kept):
    outcomes = [outcome for outcome, _ in kept]
    again = run_follow_up_bench(forms=(FORM,), seeds=1, first_seed=SEEDS[0])
    first, repeated = asdict(outcomes[0]), asdict(again[0])
    first.pop("seconds"), repeated.pop("seconds")
    assert repeated == first  # seeded: the same session, follow-up and scores
    rows = summarize(outcomes)
    assert [r["form"] for r in rows] == [FORM] and rows[0]["n"] == len(SEEDS)
    text = table(outcomes)
    assert FORM in text and "models exported" in text


def test_measure_more_continues_a_drift_in_time():
    generated = generate_session({"temporal-drift": "decline"}, seed=5)
    whites = [Patch("white", (255, 255, 255))] * 3
    combined = generated.measure_more(whites, seed=2)
    n = len(generated.session)
    t = combined.session.t_s[n:]
    # a linear decline goes on falling after the session, as its form says
    gains = combined.true_XYZ[n:, 1] / generated.true_at([[255, 255, 255]], [0.0])[0, 1]
    assert np.all(np.diff(gains) < 0)
    assert np.allclose(gains, generated.display._drift(t) / generated.display._drift(np.zeros(1)))
    # a fresh stream per seed, repeatable
    assert np.array_equal(generated.measure_more(whites, seed=2).session.XYZ, combined.session.XYZ)
    assert not np.array_equal(generated.measure_more(whites, seed=3).session.XYZ[n:],
                              combined.session.XYZ[n:])


def test_the_benches_run_from_the_workbench_command_line(capsys):
    """``bench peers`` and ``bench follow-up`` print the tables the README quotes; a bad --seeds
    is refused with the fix."""
    from workbench.cli import main

    assert main(["bench", "follow-up", "--seeds", "1", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert {row["form"] for row in document["rows"]} >= {"knee", "drive-crosstalk"}
    assert main(["bench", "peers", "--seeds", "0"]) == 2
    assert "give at least 1 session" in capsys.readouterr().err
