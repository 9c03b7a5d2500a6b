"""APL patches through the measurement sequence: plans, runner, journal, session CSV, old displays."""

import numpy as np
import pytest

from instruments.headset import HEADSET_EFFECTS, SimulatedHeadset
from instruments.patch_display import SimulatedPatchDisplay, TcpPatchDisplay
from instruments.patch_server import PatchServer
from workbench.apl import apl_fold_labels, detect_apl_dependence, evaluate_apl_holdout
from workbench.measurement.journal import read_journal
from workbench.measurement.plans import (APL_SURROUNDS, APL_WINDOWS, measurement_plan, read_plan_file)
from workbench.measurement.runner import JOURNAL_NAME, MeasurementRun, RunAborted
from workbench.measurement.simulation import modelled_plan_duration_s
from workbench.session import read_session_csv

from .conftest import ScriptedMeter

NOISE = 0.002


class NoisyMeter(ScriptedMeter):
    """The scripted meter with a relative luminance noise, as a spectroradiometer has."""

    def __init__(self, headset, seed):
        super().__init__(headset)
        self.rng = np.random.default_rng(seed)

    def measure(self, progress=None, cancel=None):
        m = super().measure(progress, cancel)
        factor = 1.0 + NOISE * self.rng.standard_normal()
        m.XYZ, m.radiance, m.Lv = m.XYZ * factor, m.radiance * factor, m.Lv * factor
        return m


def _measure(tmp_path, plan, headset, seed=0):
    run = MeasurementRun.start(tmp_path, plan, SimulatedPatchDisplay(headset), NoisyMeter(headset, seed),
                               display_name="sim")
    list(run.events())
    return read_session_csv(tmp_path / "session.csv")


def test_the_apl_plan_and_block():
    plan = measurement_plan("apl", 3)
    apl = [p for p in plan.patches if p.is_apl]
    assert len(plan) == 31 and len(apl) == 24 and plan.counts() == {"white": 6, "grey": 25}
    assert plan.patches[0].kind == plan.patches[-1].kind == "white" and not plan.patches[0].is_apl
    assert {p.window for p in apl} == set(APL_WINDOWS)
    assert {p.surround[0] for p in apl} == {0, *APL_SURROUNDS}
    assert all(p.kind == "grey" for p in apl)
    combined = measurement_plan("paper+apl", 3)
    assert combined.patches[:214] == measurement_plan("paper", 3).patches
    assert sum(p.is_apl for p in combined.patches) == 24 and len(combined) == 244
    # the instrument time the plans' documentation states
    headset = SimulatedHeadset()
    assert modelled_plan_duration_s(plan, headset) / 60 == pytest.approx(2.1, abs=0.05)
    assert modelled_plan_duration_s(combined, headset) / 60 == pytest.approx(69.3, abs=0.05)


@pytest.mark.parametrize("seed", range(3))
def test_a_hidden_apl_limit_is_measured_found_and_modelled(tmp_path, seed):
    low, high = HEADSET_EFFECTS["apl-dependence"].realistic_range
    magnitude = float(np.random.default_rng([7, seed]).uniform(low, high))
    session = _measure(tmp_path, measurement_plan("apl", seed), SimulatedHeadset({"apl-dependence": magnitude}),
                       seed)
    assert session.has_surround_data and session.window.min() == min(APL_WINDOWS)
    test = detect_apl_dependence(session, NOISE)
    assert test.z > 5, test.evidence
    for by, labels in apl_fold_labels(session).items():
        score = evaluate_apl_holdout(session, labels, by)
        assert score.luminance_error_pct < 0.5 * score.luminance_error_pct_without, score.one_line()


@pytest.mark.parametrize("seed", range(3))
def test_a_clean_headset_measured_with_the_apl_plan_gives_no_finding(tmp_path, seed):
    session = _measure(tmp_path, measurement_plan("apl", seed), SimulatedHeadset({"black-offset": 0.004}), seed)
    test = detect_apl_dependence(session, NOISE)
    assert test.testable and abs(test.z) < 3.5, test.evidence


def test_the_journal_records_the_frame_and_a_resumed_plan_keeps_it(tmp_path):
    headset = SimulatedHeadset()
    plan = measurement_plan("apl", 1)
    _measure(tmp_path, plan, headset)
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert journal.header.plan == plan
    records = {r.index: r for r in journal.records}
    for index, patch in enumerate(plan.patches):
        assert records[index].patch() == patch
    session = read_session_csv(tmp_path / "session.csv")
    assert len(session) == 31 and np.allclose(session.window, [p.window for p in plan.patches])
    assert np.allclose(session.surround, [p.surround for p in plan.patches])


def test_the_ti3_export_keeps_only_full_field_patches(tmp_path):
    from workbench.session_readers import read_ti3

    _measure(tmp_path, measurement_plan("apl", 2), SimulatedHeadset())
    assert len(read_ti3(tmp_path / "session.ti3")) == 6 + 1  # the whites and the full-field mid grey


def test_a_display_that_cannot_show_apl_patches_stops_the_run_with_a_message(tmp_path):
    headset = SimulatedHeadset()
    with PatchServer(lambda rgb: headset.show(rgb), apl_patches=False, idle_timeout_s=5.0) as server:
        server.start()
        with TcpPatchDisplay(*server.address, timeout_s=2.0) as display:
            run = MeasurementRun.start(tmp_path, measurement_plan("apl", 0), display, ScriptedMeter(headset),
                                       display_name="old server")
            with pytest.raises(RunAborted) as caught:
                list(run.events())
    assert "cannot show APL patches" in str(caught.value) and "--resume" in str(caught.value)
    assert len(read_journal(tmp_path / JOURNAL_NAME).records) == 1  # the first white was measured


def test_a_plan_file_may_give_window_and_surround(tmp_path):
    path = tmp_path / "plan.csv"
    path.write_text("kind,r,g,b,window,sr,sg,sb\nwhite,255,255,255,1,0,0,0\ngrey,255,255,255,0.05,64,64,64\n")
    plan = read_plan_file(path)
    assert not plan.patches[0].is_apl and plan.patches[1].window == 0.05
    assert plan.patches[1].surround == (64, 64, 64)
