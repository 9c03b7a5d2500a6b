"""The Qt-free Workspace and calibration setup the window drives: open, diagnose, export, resume, re-measure."""

import os
from pathlib import Path

import pytest

from instruments.cs2000.emulator import ErrorFault
from workbench.errors import InputError, WorkbenchError
from workbench.measurement.journal import read_journal
from workbench.measurement.runner import JOURNAL_NAME, PatchMeasured
from workbench.profile import load_profile
from workbench.workspace import MeasurementState, Workspace, is_profile_file, load_path, unfinished_journal

REAL = Path(os.environ.get("VR_WORKBENCH_SHARED", Path(__file__).resolve().parents[2] / "shared")) / "data" / "real"
needs_real = pytest.mark.skipif(not REAL.is_dir(), reason=f"the shared real display data is not at {REAL} "
                                                          "(set VR_WORKBENCH_SHARED to the shared/ folder)")
PROFILE = Path(__file__).resolve().parents[1] / "profiles" / "htc-vive-paper.vrprofile.json"

gui_setup = pytest.importorskip("workbench.gui.calibration_setup")  # Qt-free, but lives in the gui package


def _events(workspace):
    seen = []
    for event in ("session-changed", "diagnosis-changed", "profile-changed", "measurement-changed"):
        workspace.subscribe(event, lambda ws, event=event: seen.append(event))
    return seen


@needs_real
def test_opening_a_ti3_sets_the_session_and_its_diagnosis_and_emits_in_order():
    workspace = Workspace()
    seen = _events(workspace)
    loaded = workspace.open_path(REAL / "dell-up2516d-displaycal.ti3")
    assert seen == ["session-changed", "diagnosis-changed", "profile-changed"]
    assert workspace.session is loaded.session and workspace.diagnosis is loaded.diagnosis
    assert workspace.session_path == REAL / "dell-up2516d-displaycal.ti3"
    assert workspace.diagnosis.to_json()["session"]["validation"] == 108
    # the display just opened becomes the current profile (its diagnosed model), unsaved
    assert workspace.profile_path is None
    assert workspace.profile.device["source"] == loaded.session.source
    assert workspace.profile.display_model_type == workspace.diagnosis.extended.model_id


def test_opening_a_profile_makes_it_current_and_diagnoses_its_primaries():
    assert is_profile_file(PROFILE)
    workspace = Workspace()
    seen = _events(workspace)
    workspace.open_path(PROFILE)
    assert seen == ["session-changed", "diagnosis-changed", "profile-changed"]
    assert workspace.profile_path == PROFILE and workspace.diagnosis is not None


def test_opening_what_does_not_exist_names_it(tmp_path):
    with pytest.raises(WorkbenchError, match="nothing-here.csv: no such file"):
        load_path(tmp_path / "nothing-here.csv")


def test_export_needs_a_diagnosis_then_writes_a_valid_profile_and_makes_it_current(tmp_path):
    workspace = Workspace()
    with pytest.raises(WorkbenchError, match="nothing to export"):
        workspace.export_profile(tmp_path / "p.vrprofile.json")
    workspace.open_path(PROFILE)
    written = workspace.export_profile(tmp_path / "p.vrprofile.json")
    assert load_profile(written).display_model_type == workspace.profile.display_model_type
    assert workspace.profile_path == written


def test_measurement_state_rejects_an_unknown_status():
    workspace = Workspace()
    workspace.set_measurement(status="running", done=3, total=28)
    assert workspace.measurement == MeasurementState(status="running", done=3, total=28)
    with pytest.raises(WorkbenchError, match="unknown measurement status 'walking'"):
        workspace.set_measurement(status="walking")


def test_a_setup_refuses_what_cannot_work():
    with pytest.raises(InputError, match="cannot measure the simulated headset"):
        gui_setup.CalibrationSetup(Path("x"), instrument="/dev/ttyACM0", display="simulated")
    with pytest.raises(InputError, match="needs a host and a port"):
        gui_setup.CalibrationSetup(Path("x"), display="tcp")
    with pytest.raises(InputError, match="unknown headset effect 'glare'"):
        gui_setup.CalibrationSetup(Path("x"), effects={"glare": 0.1})


def test_the_estimate_counts_the_plan_and_dark_patches_take_longer():
    plan = gui_setup.CalibrationSetup(Path("x"), plan_name="quick", seed=1).plan()
    estimate = gui_setup.plan_estimate(plan)
    assert estimate.patches == 28 and estimate.counts["validation"] == 10
    dark = gui_setup.plan_estimate(type(plan)("dark", tuple(p for p in plan.patches if p.kind == "black") * 4, 1))
    bright = gui_setup.plan_estimate(type(plan)("bright", tuple(p for p in plan.patches if p.kind == "white")[:1] * 4, 1))
    assert dark.instrument_s > 2 * bright.instrument_s


def test_a_cancelled_run_is_unfinished_and_resuming_with_remeasure_finishes_it(tmp_path):
    setup = gui_setup.CalibrationSetup(tmp_path, plan_name="quick", seed=4,
                                       faults=(ErrorFault("ER83", command="MEAS,1", nth=2, line=2),))
    with gui_setup.open_run(setup) as run:
        for event in run.events():
            if isinstance(event, PatchMeasured) and event.done == 4:
                run.cancel()
    journal = unfinished_journal(tmp_path)
    assert journal is not None and not journal.latest()[1].ok and "ER83" in journal.latest()[1].reason
    with gui_setup.open_run(gui_setup.CalibrationSetup(tmp_path, plan_name="quick", remeasure=(0,))) as run:
        summary = list(run.events())[-1].summary
    assert summary.status == "finished" and summary.measured == 28 and not summary.failed
    assert unfinished_journal(tmp_path) is None
    journal = read_journal(tmp_path / JOURNAL_NAME)
    assert [r.index for r in journal.superseded_records()] == [0, 1]
    assert journal.resumes[-1]["remeasure"] == [0]
