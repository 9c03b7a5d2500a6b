"""The adaptive plan: within its budget, every decision journaled with its reason, the same decisions
after a crash, the validation colours never read, greys and mixtures where the channels interact.

The meter measures the simulated headset noiselessly and advances a modelled session clock by the
CS-2000 emulator's timing model (announcing its countdown as ``MEAS,1`` would), so a run is a
deterministic function of its patches: a run cancelled half-way and resumed must decide exactly
what an uninterrupted run decides.
"""

from collections import Counter
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from instruments.cs2000 import measurement_timing, radiance_to_luminance
from instruments.headset import SimulatedHeadset
from workbench.cli import main
from workbench.measurement.adaptive import (
    DRIFT_REFERENCE_INTERVAL_S,
    MIN_VALIDATION,
    PRIMARY_READINGS,
    TIME_CAP_SHARE,
    AdaptivePlanner,
    AdaptiveSettings,
    adaptive_core_plan,
    plan_state,
    replay_decisions,
    _with_drift_references,
    validation_count,
    validation_patches,
)
from workbench.measurement.journal import read_journal
from workbench.measurement.patch_cost import fit_patch_cost
from workbench.measurement.plans import measurement_plan
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun, PatchMeasured
from workbench.measurement.simulation import ModelledSessionClock

from .conftest import RecordingDisplay, ScriptedMeter

SEED = 11
SETTINGS = AdaptiveSettings(seed=SEED, budget_min=19.0, validation=6, floor_dE00_per_min=0.002)
EFFECTS = {"channel-interaction": 0.1}


class TimedMeter(ScriptedMeter):
    """The scripted meter with the emulator's timing: the clock advances, the countdown is announced."""

    def __init__(self, headset, clock):
        super().__init__(headset)
        self.clock = clock

    def measure(self, progress=None, cancel=None):
        measured = super().measure(progress, cancel)
        duration_s, countdown_s = self.seconds()
        self.clock.advance(duration_s)
        return SimpleNamespace(**vars(measured), measurement_time_s=countdown_s)

    def seconds(self) -> tuple:
        """(seconds the patch takes, the countdown announced) for the patch shown."""
        timing = measurement_timing(radiance_to_luminance(self.headset.current_radiance()))
        return timing.duration_s, timing.measurement_s


def _run(out, cancel_after=None, resume=False):
    """Measure (or resume) the adaptive plan in ``out``; cancel after ``cancel_after`` patches."""
    headset = SimulatedHeadset(EFFECTS)
    display = RecordingDisplay(headset)
    if resume:
        journal = read_journal(out / JOURNAL_NAME)
        clock = ModelledSessionClock(journal.session_end_s())
        run = MeasurementRun.resume_session(out, display, TimedMeter(headset, clock), journal=journal,
                                            clock=lambda h, j: clock, planner=AdaptivePlanner(SETTINGS))
    else:
        clock = ModelledSessionClock()
        run = MeasurementRun.start(out, adaptive_core_plan(SEED), display, TimedMeter(headset, clock),
                                   settings={"adaptive": SETTINGS.to_json()}, clock=lambda h, j: clock,
                                   planner=AdaptivePlanner(SETTINGS))
    measured = 0
    for event in run.events():
        if isinstance(event, PatchMeasured):
            measured += 1
            if cancel_after is not None and measured == cancel_after:
                run.cancel()
    return read_journal(out / JOURNAL_NAME)


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """An uninterrupted adaptive run on a headset whose channels interact (a 10 % power limit)."""
    return _run(tmp_path_factory.mktemp("adaptive") / "session")


def _measured(decisions):
    return [d for d in decisions if d["action"] == "measure"]


def test_stops_within_budget_with_every_decision_explained(whole):
    decisions = whole.decisions
    assert decisions and decisions[-1]["action"] == "stop"
    assert sum(d["action"] == "stop" for d in decisions) == 1
    assert not whole.pending_indices()
    for d in _measured(decisions):
        assert "predicted held-out ΔE00" in d["reason"] and " → " in d["reason"] and " s" in d["reason"]
        assert d["predicted_after_dE00"] < d["predicted_dE00"]
        assert len(d["patches"]) == 1
    assert "stop:" in decisions[-1]["reason"]
    budget_s = 60 * SETTINGS.budget_min
    assert all(d["budget_s"] == budget_s for d in decisions)
    # the planner reserved the validation colours' time: what was measured stays within the budget,
    # give or take what the cost model mispredicts of the last patches
    total = sum(r.duration_s for r in whole.records)
    stop = decisions[-1]
    assert stop["elapsed_s"] + stop["cost_s"] <= budget_s
    assert total <= 1.1 * budget_s
    state = plan_state(whole)
    assert state.stopped and state.planned == len(whole.header.plan) and state.time_left_s >= 0
    assert len(state.history) == len(decisions)


def test_an_interaction_gets_greys_and_mixtures(whole):
    kinds = [p[0] for d in _measured(whole.decisions) for p in d["patches"]]
    assert {"grey", "mixture"} & set(kinds)
    assert sum(k in ("grey", "mixture") for k in kinds) >= len(kinds) / 2
    assert any("how the channels combine" in d["reason"] for d in _measured(whole.decisions))


def test_the_first_decision_reads_each_primary_again(whole):
    first = whole.decisions[0]
    assert first["action"] == "primaries" and "column of the matrix" in first["reason"]
    assert [tuple(p[1:4]) for p in first["patches"]] == [(255, 0, 0), (0, 255, 0), (0, 0, 255)] * (PRIMARY_READINGS - 1)
    readings = Counter(tuple(r.rgb) for r in whole.records if r.ok and r.kind != "validation")
    assert all(readings[p] == PRIMARY_READINGS for p in ((255, 0, 0), (0, 255, 0), (0, 0, 255)))
    assert sum(d["action"] == "primaries" for d in whole.decisions) == 1


def test_drift_references_by_elapsed_time(whole):
    core = len(adaptive_core_plan(SEED))
    # the planner's references, from the core's last white on (the core's whites follow its sweeps)
    # to the validation colours' first
    validation = min(r.index for r in whole.records if r.kind == "validation")
    whites = [r for r in whole.records if r.kind == "white" and core - 1 <= r.index < validation]
    gaps = np.diff([r.t_s for r in whites])
    references = [d for d in whole.decisions if d["action"] == "drift-reference"]
    assert references and all("since the last white" in d["reason"] for d in references)
    # a reference is due DRIFT_REFERENCE_INTERVAL_S after the last white; a patch in flight may
    # add its own seconds
    longest_patch = max(r.duration_s for r in whole.records if r.kind != "black")
    assert gaps.size >= 2
    assert np.all(gaps <= DRIFT_REFERENCE_INTERVAL_S + 2 * longest_patch)


def test_the_validation_colours_carry_drift_references():
    """A white each DRIFT_REFERENCE_INTERVAL_S of the validation colours' predicted time, and two
    last whites one after the other: the validation colours are corrected for drift as the fit rows
    are, and the drift correction's reference state (the mean of the last two whites) is one
    moment, the session's end, not two a minute apart."""
    validation = validation_patches(SEED, 30)
    dark = {p.rgb for p in validation[5:7]}  # two dark ones, a minute each

    def seconds(patches):
        return sum(60.0 if p.rgb in dark else 4.0 for p in patches)

    closing = _with_drift_references(validation, seconds)
    assert [p for p in closing if p.kind == "validation"] == list(validation)
    assert [p.kind for p in closing[-3:]] == ["validation", "white", "white"]
    assert sum(p.kind == "white" for p in closing) >= 5
    since = 0.0
    for patch in closing:
        since = 0.0 if patch.kind == "white" else since + seconds([patch])
        assert since <= DRIFT_REFERENCE_INTERVAL_S or seconds([patch]) >= DRIFT_REFERENCE_INTERVAL_S
    assert [p.kind for p in _with_drift_references(validation[:3], seconds)] == ["validation"] * 3 + ["white"] * 2


def test_resume_after_a_crash_reproduces_the_decisions(whole, tmp_path):
    out = tmp_path / "session"
    core = len(adaptive_core_plan(SEED))
    first = _run(out, cancel_after=core + 8)
    assert 0 < len(first.decisions) < len(whole.decisions)
    resumed = _run(out, resume=True)

    def essentials(decisions):
        return [(d["action"], d["patches"], d["reason"]) for d in decisions]

    assert essentials(resumed.decisions) == essentials(whole.decisions)
    assert [r.rgb for r in resumed.ok_records()] == [r.rgb for r in whole.ok_records()]


def test_replay_gives_the_journaled_decisions(whole):
    pairs = replay_decisions(whole)
    assert len(pairs) == len(whole.decisions)
    for journaled, replayed in pairs:
        assert replayed["patches"] == journaled["patches"]
        assert replayed["reason"] == journaled["reason"]


def test_validation_colours_are_never_read(whole):
    # the validation colours come only with the stop, last
    for d in whole.decisions[:-1]:
        assert all(p[0] != "validation" for p in d["patches"])
    assert [p[0] for p in whole.decisions[-1]["patches"]][:-2] == ["validation"] * SETTINGS.validation
    # and their measurements change nothing: with them replaced by nonsense, every decision replays
    nonsense = tuple(replace(r, XYZ=(1e3, 1e-3, 5e2), Lv=1e-3, duration_s=r.duration_s)
                     if r.kind == "validation" else r for r in whole.records)
    tampered = replace(whole, records=nonsense)
    for journaled, replayed in replay_decisions(tampered):
        assert replayed["reason"] == journaled["reason"]
    assert all(r.kind != "validation" for r in AdaptivePlanner.fit_records(whole))


def test_patch_cost_comes_from_the_session():
    clock = ModelledSessionClock()
    records = [SimpleNamespace(ok=True, Lv=L, duration_s=d, measurement_time_s=t, rgb=rgb)
               for L, d, t, rgb in ((0.0, 252.0, 242, (0, 0, 0)), (100.0, 3.0, 2, (255, 255, 255)),
                                    (1.0, 30.0, 24, (0, 0, 64)), (10.0, 8.0, 6, (0, 0, 128)))]
    del clock
    model = fit_patch_cost(records)
    seconds = model.seconds([100.0, 10.0, 1.0, 0.1, 0.0])
    assert np.all(np.diff(seconds) >= 0)  # darker never cheaper
    assert seconds[0] == pytest.approx(3.0) and seconds[2] == pytest.approx(30.0)
    assert 30.0 < seconds[3] <= 252.0 and seconds[4] == pytest.approx(252.0)
    assert "countdown" in model.describe()


def test_a_patch_that_reads_no_light_costs_what_the_black_did():
    # a toe crushes grey 8 to black: it reads no light and takes the instrument's limit, as the
    # black does. Taken for the darkest lit patch (at the luminance floor) it drew the cost of
    # everything darker than the darkest lit one on a line to it: a sweep point the toe also
    # crushes was predicted at a minute, not four, and the paper plan's time 32 min, not 46
    # (it took 55 on the plans bench's toe of seed 43003)
    records = [SimpleNamespace(ok=True, Lv=L, duration_s=d, measurement_time_s=None, rgb=rgb)
               for L, d, rgb in ((0.0002, 252.0, (0, 0, 0)), (165.0, 3.0, (255, 255, 255)),
                                 (-0.0002, 252.0, (8, 8, 8)), (0.6, 20.4, (0, 0, 32)),
                                 (0.94, 17.0, (0, 0, 64)), (1.34, 14.7, (0, 0, 96)),
                                 (2.26, 12.3, (16, 16, 16)))]
    seconds = fit_patch_cost(records).seconds([2.26, 0.1, 0.001, 0.0])
    assert seconds[0] == pytest.approx(12.3)
    assert 20.4 < seconds[1] < 252.0  # the darkest lit patches' slope, not the floor's
    assert seconds[2] == pytest.approx(252.0) and seconds[3] == pytest.approx(252.0)
    # its reading's noise may put it a little above the black's: its time says the same
    records[2].Lv = 0.0003
    assert fit_patch_cost(records).seconds([0.001])[0] == pytest.approx(252.0)


def test_measure_cli_adaptive(tmp_path, capsys):
    out = tmp_path / "session"
    code = main(["measure", "--simulate", "--plan", "adaptive", "--seed", "4", "--budget-min", "16",
                 "--validation", "5", "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    assert "held-out" in printed and "95 % CI" in printed
    journal = read_journal(out / JOURNAL_NAME)
    assert journal.header.settings["adaptive"]["budget_min"] == 16
    assert journal.decisions[-1]["action"] == "stop"


def test_measure_cli_refuses_adaptive_options_elsewhere(tmp_path, capsys):
    code = main(["measure", "--simulate", "--plan", "quick", "--budget-min", "5", "--out", str(tmp_path / "x")])
    assert code == 2
    assert "--budget-min" in capsys.readouterr().err


@pytest.mark.slow
def test_bench_plans_prints_its_table(capsys):
    code = main(["bench", "plans", "--sessions", "2", "--scenarios", "headset clean"])
    printed = capsys.readouterr().out
    assert code == 0
    for plan in ("paper", "paper+greys", "adaptive"):
        assert plan in printed
    assert "acceptance over 2 displays" in printed


def test_bench_plans_measures_only_the_plans_named(capsys, monkeypatch):
    from tests.diagnostics import plans_bench

    asked = {}
    monkeypatch.setattr(plans_bench, "run_plans_bench",
                        lambda sessions, names, plans, speed_mode:
                        asked.update(plans=plans, speed_mode=speed_mode) or [])
    monkeypatch.setattr(plans_bench, "PlansBenchResult",
                        lambda outcomes, markdown: SimpleNamespace(summary=lambda: "table"))
    assert main(["bench", "plans", "--plans", "adaptive", "paper"]) == 0
    assert asked == {"plans": ("adaptive", "paper"), "speed_mode": 0}
    assert main(["bench", "plans", "--plans", "adaptive", "--speed-mode", "fast"]) == 0
    assert asked == {"plans": ("adaptive",), "speed_mode": 1}
    assert main(["bench", "plans", "--plans", "adaptive", "fast"]) == 2
    assert ("--plans: unknown 'fast'; use some of paper, paper+greys, adaptive, paper-repeat"
            in capsys.readouterr().err)
    assert main(["bench", "plans", "--plans", "paper", "paper-repeat", "adaptive"]) == 0
    assert asked == {"plans": ("paper", "paper-repeat", "adaptive"), "speed_mode": 0}


def test_paper_repeat_is_the_paper_plan_with_another_noise_draw(tmp_path):
    """The bench's ``paper-repeat`` measures the same patches on the same display as ``paper``; only
    the instrument's noise differs (its own stream), by about the display's repeatability."""
    from tests.diagnostics import plans_bench

    kind, effects = plans_bench.scenarios()["clean"]
    first, again = (plans_bench.measure_plan(plan, "clean", kind, effects, 7, tmp_path / plan)
                    for plan in ("paper", "paper-repeat"))
    assert np.array_equal(first[0].rgb, again[0].rgb) and np.array_equal(first[0].kind, again[0].kind)
    lit = first[0].XYZ[:, 1] > 1.0
    ratio = again[0].XYZ[lit, 1] / first[0].XYZ[lit, 1]
    assert not np.allclose(ratio, 1.0, rtol=1e-6, atol=0.0)
    assert np.std(ratio) < 10 * first[5] + 1e-3  # noise of the order of one reading's, not a new display
    rgb = np.array([[40, 80, 120], [255, 255, 255]], dtype=float)
    assert np.allclose(first[1](rgb), again[1](rgb), rtol=1e-3)  # the same true display


def test_bench_acceptance_sets_adaptive_beside_the_paper_plans_repeatability():
    from tests.diagnostics import plans_bench

    def outcome(plan, seed, hidden):
        return plans_bench.PlanOutcome("clean", "generator", seed, plan, {}, 100.0, 10, hidden, hidden,
                                       hidden, (), "baseline", 0, 0.0, (0.0, 0.0))

    hidden = {1: (0.05, 0.10, 0.06), 2: (0.10, 0.05, 0.08), 3: (0.05, 0.05, 0.09)}  # paper, repeat, adaptive
    outcomes = [outcome(plan, seed, value) for seed, values in hidden.items()
                for plan, value in zip(("paper", "paper-repeat", "adaptive"), values)]
    line = [t for t in plans_bench.table(outcomes).splitlines()
            if t.startswith("the paper plan's repeatability")]
    assert line == ["the paper plan's repeatability (paper-repeat: the same 3 displays and patches, "
                    "another draw of the instrument's noise): hidden mean ΔE00 0.0667 and 0.0667; "
                    "the repeat misses the first + 0.02 on 1, the first the repeat's on 1; adaptive "
                    "misses the first on 1, the repeat on 2"]
    assert not [t for t in plans_bench.table(outcomes[2::3] + outcomes[::3]).splitlines()
                if t.startswith("the paper plan's repeatability")]  # no repeat measured: no such line


def test_no_fold_holds_every_white():
    """An adaptive session's few whites can all fall in one cross-validation fold; that fold's
    training set would have no white, and a candidate fitted to the white (the power limit) could
    not be cross-validated at all (a knee display was exported with the wrong model for it)."""
    from workbench.diagnostics.cross_validation import FOLDS, fold_of_rows

    rgb = np.zeros((4 * FOLDS, 3))
    rgb[:, 0] = np.arange(4 * FOLDS) + 10  # red sweep points, free rows
    rgb[::FOLDS] = 255  # every white lands in fold 0
    class Rows(SimpleNamespace):
        def __len__(self):
            return len(self.rgb)

    context = SimpleNamespace(raw=Rows(rgb=rgb), copies=np.zeros(len(rgb), bool))
    fold = fold_of_rows(context)
    white = np.all(rgb >= 255, axis=1)
    for k in range(FOLDS):
        assert (white & (fold != k)).any(), f"fold {k}'s training set has no white"
    assert (fold >= 0).sum() >= len(rgb) - 1  # one white kept in every training set, no more


def test_validation_count_keeps_the_session_within_the_cap():
    costs = [10.0] * 30
    # 100 s of core, 5 s whites: a cap of 330 s leaves room for 20 colours, with the two last whites
    # and the three among them (one before every seventh colour: 10 s each, a white each 60 s) — 22
    # when only one last white was counted, and the session passed the cap by the others
    assert validation_count(30, 100.0, 5.0, costs, 1000.0) == 20
    assert 100.0 + 5 * (2 + 3) + 10 * 20 <= TIME_CAP_SHARE * 1000 < 100.0 + 5 * (2 + 3) + 10 * 21
    assert validation_count(30, 100.0, 5.0, costs, 10_000.0) == 30  # room for all: all
    assert validation_count(30, 400.0, 5.0, costs, 1000.0) == MIN_VALIDATION  # never fewer
    assert validation_count(5, 400.0, 5.0, costs, 1000.0) == 5  # unless fewer were asked for


class FlatMeter(TimedMeter):
    """Every patch 3 s, dark or bright (a short dark end: an instrument in a fast mode)."""

    def seconds(self) -> tuple:
        return 3.0, 2


def test_where_every_patch_costs_the_same_fewer_validation_colours_keep_the_time_share(tmp_path):
    settings = AdaptiveSettings(seed=SEED)  # no budget: a share of the paper plan's time
    headset = SimulatedHeadset({})
    clock = ModelledSessionClock()
    run = MeasurementRun.start(tmp_path / "s", adaptive_core_plan(SEED), RecordingDisplay(headset),
                               FlatMeter(headset, clock), settings={"adaptive": settings.to_json()},
                               clock=lambda h, j: clock, planner=AdaptivePlanner(settings))
    for _ in run.events():
        pass
    journal = read_journal(tmp_path / "s" / JOURNAL_NAME)
    stop = journal.decisions[-1]
    measured = sum(p[0] == "validation" for p in stop["patches"])
    assert MIN_VALIDATION <= measured < settings.validation
    assert all(d["validation"] == measured for d in journal.decisions)
    assert f"{measured} of the {settings.validation} asked for" in stop["reason"]
    # the core is most of the cap here: no room for the primaries' further readings
    assert not any(d["action"] == "primaries" for d in journal.decisions)
    paper_s = 3.0 * len(measurement_plan("paper", SEED))
    assert sum(r.duration_s for r in journal.records) <= TIME_CAP_SHARE * paper_s + 3.0
    for journaled, replayed in replay_decisions(journal):
        assert replayed["patches"] == journaled["patches"] and replayed["reason"] == journaled["reason"]


def _core_model(effects, seed):
    """The planning model of the adaptive core measured noiselessly on a generated display, the
    display, and the paper plan's colours."""
    from tests.diagnostics.independent_generator import generate_session
    from workbench.measurement.planning_model import PlanningModel, PlanningRows, planning_colours

    display = generate_session(effects, seed=seed).display
    core = adaptive_core_plan(seed)
    rgb = np.array([p.rgb for p in core.patches], dtype=float)
    rows = PlanningRows(rgb=rgb, XYZ=display.light(rgb), kind=np.array([p.kind for p in core.patches]))
    model = PlanningModel(rows, lambda Y: 0.001 * np.ones_like(np.asarray(Y, dtype=float)), 0.001,
                          planning_colours(seed))
    paper = np.array([p.rgb for p in measurement_plan("paper", seed).patches], dtype=float)
    return model, display, paper


@pytest.mark.parametrize("form", ["soft-toe", "shoulder"])
def test_the_paper_plans_dark_sweep_points_are_predicted_from_the_greys(form):
    from workbench.measurement.adaptive import paper_luminance

    model, display, paper = _core_model({"tone-curve-shape": form}, 0)
    dark = ((paper > 0).sum(axis=1) == 1) & (paper.max(axis=1) < 32)  # below the core's sweeps
    true = display.light(paper[dark])[:, 1]
    surrogate = np.maximum(model.predict(paper[dark])[:, 1], 1e-9)
    corrected = np.maximum(paper_luminance(model, paper)[dark], 1e-9)
    assert np.mean(np.abs(np.log(corrected / true))) < 0.5 * np.mean(np.abs(np.log(surrogate / true)))


def test_on_a_clean_display_the_paper_plan_is_predicted_as_the_surrogate_does():
    from workbench.measurement.adaptive import paper_luminance

    model, display, paper = _core_model({}, 0)
    surrogate = np.maximum(model.predict(paper)[:, 1], 0.0)
    assert np.allclose(paper_luminance(model, paper), surrogate, rtol=0.05, atol=1e-3)


def test_with_a_budget_the_primaries_are_read_as_often_as_it_leaves_room_for():
    """With ``--budget-min`` the further readings are held to the budget as the time cap holds them
    without one: as many as leave room for the validation colours and their whites, not six or
    none."""
    planner = AdaptivePlanner(AdaptiveSettings(seed=SEED, budget_min=5.0, validation=6))

    def seconds(patches):
        return 10.0 * len(patches)

    closing = _with_drift_references(planner.validation, seconds)  # six colours, two whites: 80 s
    assert seconds(closing) == 80.0
    assert planner._repeats_fit(seconds, 300.0 - 80.0, None)
    assert not planner._repeats_fit(seconds, 300.0 - 79.0, None)
    # without a budget or a predicted paper plan, nothing holds them back
    assert AdaptivePlanner(AdaptiveSettings(seed=SEED, validation=6))._repeats_fit(seconds, 1e6, None)
