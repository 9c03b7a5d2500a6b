"""Fit & diagnose → "Measure the N patches that identify this": the follow-up measured from the window.

A simulated quick session hiding a channel interaction is opened; the interaction's card carries the
button with the follow-up's own figures; clicking it measures the follow-up into the same measurement
directory on the Calibrate page (same setup), and the new diagnosis reads the greys. A session opened
from a file outside a measurement directory gets the plan file put into the Calibrate form instead.
"""

import shutil

import pytest

from tests.gui import require_window

require_window("pyqtgraph")

from PySide6.QtCore import Qt  # noqa: E402

from workbench.cli import main  # noqa: E402
from workbench.diagnostics.extension import interaction_shape  # noqa: E402
from workbench.diagnostics.follow_up import propose_follow_up  # noqa: E402
from workbench.measurement.journal import read_journal  # noqa: E402
from workbench.measurement.plans import read_plan_file  # noqa: E402
from workbench.measurement.runner import JOURNAL_NAME  # noqa: E402

pytestmark = pytest.mark.gui

RUN_TIMEOUT_MS = 60_000
QUICK = 28


@pytest.fixture(autouse=True)
def _config_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("VR_WORKBENCH_CONFIG_DIR", str(tmp_path / "config"))


@pytest.fixture
def session_dir(tmp_path):
    out = tmp_path / "session"
    assert main(["measure", "--simulate", "--plan", "quick", "--seed", "4", "--time-scale", "0",
                 "--effect", "channel-interaction:0.1", "--out", str(out)]) == 0
    return out


def _open(qtbot, window, path):
    with qtbot.waitSignal(window.file_loaded, timeout=RUN_TIMEOUT_MS):
        window.open_path(path)
    diagnose = window.pages["diagnose"]
    diagnose.finish_drawing()
    return diagnose


def test_the_button_measures_the_follow_up_into_the_same_directory_with_the_same_setup(
        qtbot, window, session_dir):
    diagnose = _open(qtbot, window, session_dir)
    follow_up = propose_follow_up(window.workspace.diagnosis)
    n = follow_up.patch_count
    button = diagnose.cards.action_button
    assert n > 0 and button is not None
    assert button.text() == f"Measure the {n} patches that identify this — about {follow_up.minutes()} min"
    card = next(c for c in diagnose.cards.cards if c.action is button)
    assert card.card.effect == "channel-interaction"

    calibrate = window.pages["calibrate"]
    calibrate.form.time_scale.setValue(0.0)
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    plan = read_plan_file(session_dir / "follow-up-1.csv")
    assert plan.patches == follow_up.patches
    journal = read_journal(session_dir / JOURNAL_NAME)
    assert len(journal.header.plan) == QUICK + n and journal.pending_indices() == []
    assert [r.patch() for r in journal.ok_records()[QUICK:]] == list(plan.patches)
    assert len(journal.additions) == 1
    assert journal.header.display.startswith("simulated OLED HMD")  # shown as the session was
    assert calibrate.progress.value() == QUICK + n
    # the window now shows the diagnosis of every measurement: the shape is fitted on the greys
    assert len(window.workspace.diagnosis.session) == QUICK + n
    assert interaction_shape(window.workspace.diagnosis.context)[1] == "greys"
    assert window.current_page_key() == "diagnose"


def test_a_session_without_a_measurement_directory_gets_the_plan_file_in_the_form(
        qtbot, window, session_dir, tmp_path):
    elsewhere = tmp_path / "copied.csv"
    shutil.copy(session_dir / "session.csv", elsewhere)
    diagnose = _open(qtbot, window, elsewhere)
    button = diagnose.cards.action_button
    assert button is not None
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    calibrate = window.pages["calibrate"]
    form = calibrate.form
    assert window.current_page_key() == "calibrate" and not calibrate.running
    assert form.plan.currentData() == "file"
    assert read_plan_file(form.plan_file.text()).patches == diagnose.follow_up.patches
    assert "new session" in calibrate.message.text()
    assert not (tmp_path / "follow-up-1.csv").exists()  # nothing written beside someone else's file


def test_a_clean_session_has_no_button(qtbot, window, tmp_path):
    out = tmp_path / "clean"
    assert main(["measure", "--simulate", "--plan", "quick", "--seed", "3", "--time-scale", "0",
                 "--out", str(out)]) == 0
    diagnose = _open(qtbot, window, out)
    assert diagnose.cards.action_button is None and diagnose.follow_up.patches == ()
