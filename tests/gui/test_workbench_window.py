"""The workbench window, clicked through as a user would: calibrate (simulated), pause, cancel and resume,
an instrument error and its re-measurement, re-measuring a finished patch, opening a real .ti3, exporting."""

import gc
import logging
import os
from pathlib import Path

import numpy as np
import pytest

from tests.gui import require_window

require_window("pyqtgraph")

from PySide6.QtCore import Qt  # noqa: E402

from instruments.cs2000.emulator import ErrorFault  # noqa: E402
from workbench.gui.calibration_setup import open_run  # noqa: E402
from workbench.gui.main_window import PAGES, MainWindow, UnavailablePage, _make_page  # noqa: E402
from workbench.gui.settings import WindowSettings  # noqa: E402
from workbench.measurement.journal import read_journal  # noqa: E402
from workbench.measurement.runner import JOURNAL_NAME, PatchMeasured, RunPaused  # noqa: E402
from workbench.profile import load_profile  # noqa: E402
from workbench.workspace import Workspace  # noqa: E402

pytestmark = pytest.mark.gui

REAL = Path(os.environ.get("VR_WORKBENCH_SHARED", Path(__file__).resolve().parents[3] / "shared")) / "data" / "real"
RUN_TIMEOUT_MS = 60_000
QUICK = 28


@pytest.fixture(autouse=True)
def _config_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("VR_WORKBENCH_CONFIG_DIR", str(tmp_path / "config"))


def _dispose(window) -> None:
    """Stop the window's threads, delete it and collect its wrappers now, not in a later test."""
    from PySide6.QtWidgets import QApplication

    window.shutdown()
    window.close()
    window.deleteLater()
    QApplication.processEvents()
    gc.collect()


@pytest.fixture
def window(qtbot, tmp_path):
    window = MainWindow(Workspace(), WindowSettings(tmp_path / "config"))
    window.show()
    yield window
    _dispose(window)


def _configure(window, out_dir, *, time_scale=0.0, seed=11, plan="quick"):
    """Fill in the form as a user does: simulated CS-2000 and headset, a plan, an output directory."""
    form = window.pages["calibrate"].form
    form.instrument.setCurrentIndex(form.instrument.findData("simulated"))
    form.display.setCurrentIndex(form.display.findData("simulated"))
    form.plan.setCurrentIndex(form.plan.findData(plan))
    form.seed.setValue(seed)
    form.time_scale.setValue(time_scale)
    check, magnitude = form.effects["channel-interaction"]
    check.setChecked(True)
    magnitude.setValue(0.1)
    form.out_dir.setText(str(out_dir))
    return window.pages["calibrate"]


def _click(qtbot, button):
    assert button.isEnabled(), f"{button.text()!r} is disabled"
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)


@pytest.mark.slow
def test_a_full_simulated_calibration_fills_the_plots_shows_the_diagnosis_and_exports_a_valid_profile(
        qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "run", plan="paper")
    assert "214 patches" in calibrate.form.estimate.text() and "instrument time" in calibrate.form.estimate.text()
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.start_button)
    assert calibrate.plots.point_counts() == {"ramp-r": 51, "ramp-g": 51, "ramp-b": 51, "white": 10}
    assert calibrate.progress.value() == 214
    assert all(calibrate.patches.status(i) == "ok" for i in range(214))
    assert window.current_page_key() == "diagnose"
    assert "— run —" in window.windowTitle()  # the measurement directory names the session

    diagnose = window.pages["diagnose"]
    diagnose.finish_drawing()  # the page draws one part per event-loop turn
    assert window.workspace.diagnosis is not None
    assert diagnose.table.rowCount() == 50
    worst_first = diagnose.table.values(2)
    assert worst_first == sorted(worst_first, reverse=True)
    found = [f["effect"] for f in window.workspace.diagnosis.to_json()["findings"]]
    assert [card.card.effect for card in diagnose.cards.cards] == found and "channel-interaction" in found
    assert "baseline" in diagnose.summary.text() and "extended" in diagnose.summary.text()
    assert diagnose.fits.fits[0].getPlotItem().listDataItems()[0].xData is not None
    report = diagnose.write_report(tmp_path / "report.html")
    assert "Display diagnosis" in report.read_text()

    window.show_page("export")
    export = window.pages["export"]
    export.path.setText(str(tmp_path / "headset.vrprofile.json"))
    with qtbot.waitSignal(export.exported, timeout=5000):
        _click(qtbot, export.export_button)
    profile = load_profile(tmp_path / "headset.vrprofile.json")  # validates against the schema
    assert profile.display_model_type == window.workspace.diagnosis.extended.model_id
    assert "wrote" in export.status.text() and '"display_model"' in export.written.toPlainText()
    assert window.workspace.profile_path == tmp_path / "headset.vrprofile.json"
    assert "headset.vrprofile.json" in window.windowTitle()
    assert export.bundle_path.text() == str(tmp_path / "headset-bundle")
    with qtbot.waitSignal(export.bundle_written, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, export.bundle_button)
    manifest = (tmp_path / "headset-bundle" / "bundle.json").read_text()
    assert "display_inverse.cube" in manifest and "wrote" in export.bundle_status.text()


def test_pause_holds_the_run_and_resume_finishes_it(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "run", time_scale=0.004)
    _click(qtbot, calibrate.start_button)
    qtbot.waitUntil(lambda: window.workspace.measurement.done >= 1, timeout=RUN_TIMEOUT_MS)
    with qtbot.waitSignal(calibrate.worker.event, timeout=RUN_TIMEOUT_MS,
                          check_params_cb=lambda e: isinstance(e, RunPaused)):
        _click(qtbot, calibrate.pause_button)
    assert window.workspace.measurement.status == "paused"
    done = window.workspace.measurement.done
    assert done < QUICK
    qtbot.wait(400)
    assert window.workspace.measurement.done == done  # nothing is measured while paused
    assert calibrate.pause_button.text() == "Resume"
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.pause_button)
    assert window.workspace.measurement.status == "finished" and window.workspace.measurement.done == QUICK


def test_cancel_then_resume_continues_the_journal(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "run", time_scale=0.004)
    _click(qtbot, calibrate.start_button)
    qtbot.waitUntil(lambda: window.workspace.measurement.done >= 3, timeout=RUN_TIMEOUT_MS)
    with qtbot.waitSignal(calibrate.run_finished, timeout=RUN_TIMEOUT_MS) as finished:
        _click(qtbot, calibrate.cancel_button)
    assert finished.args[0].status == "cancelled" and finished.args[0].measured < QUICK
    qtbot.waitUntil(lambda: not calibrate.running, timeout=10_000)
    assert calibrate.start_button.text() == "Resume"
    calibrate.form.time_scale.setValue(0.0)
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.start_button)
    journal = read_journal(tmp_path / "run" / JOURNAL_NAME)
    assert len(journal.resumes) == 1 and len(journal.ok_records()) == QUICK
    assert calibrate.start_button.text() == "Start"


def test_an_instrument_error_is_shown_and_the_patch_re_measured(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "run")
    setup = calibrate.form.setup(faults=(ErrorFault("ER83", command="MEAS,1", nth=3, line=2),))
    # Wait for the finished run's session to be loaded too: its loader's
    # session_loaded must not be mistaken for the re-measure's below.
    with qtbot.waitSignals([calibrate.run_finished, calibrate.session_loaded],
                           timeout=RUN_TIMEOUT_MS, order="strict"):
        calibrate.start(setup)  # the emulator is told to fail the third measurement
    assert calibrate.patches.status(2) == "FAILED"
    assert "ER83" in calibrate.patches.note(2) and "knob" in calibrate.patches.note(2)
    assert "1 failed" in calibrate.patches.failures.text()
    assert "patch #2 failed" in calibrate.message.text()
    qtbot.waitUntil(lambda: not calibrate.running, timeout=10_000)
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.patches.remeasure_failed)
    assert calibrate.patches.status(2) == "ok"
    assert "supersedes the earlier failed record" in calibrate.patches.note(2)
    assert calibrate.patches.failed_indices() == []


def test_re_measuring_a_finished_patch_keeps_both_records_and_the_newer_wins(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "run")
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.start_button)
    calibrate.patches.select([5])
    assert calibrate.patches.selected_indices() == [5]
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.patches.remeasure_selected)
    journal = read_journal(tmp_path / "run" / JOURNAL_NAME)
    older, newer = [r for r in journal.records if r.index == 5]
    assert journal.latest()[5] is newer and journal.superseded_records() == [older]
    assert journal.resumes[-1]["remeasure"] == [5]
    assert "re-measured; supersedes the earlier ok record" in calibrate.patches.note(5)
    session_row = window.workspace.session.XYZ[5]
    assert list(session_row) == pytest.approx(list(newer.XYZ), rel=1e-5)


def test_reopening_a_killed_session_offers_to_resume_it(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "killed")
    with open_run(calibrate.form.setup()) as run:  # a run that stops after 6 patches, as if killed
        for event in run.events():
            if isinstance(event, PatchMeasured) and event.done == 6:
                run.cancel()
    asked = []
    window.ask_resume = lambda journal: asked.append(journal) or True
    _configure(window, tmp_path / "elsewhere")
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        window.open_path(tmp_path / "killed")
    assert len(asked) == 1 and len(asked[0].ok_records()) == 6
    assert len(read_journal(tmp_path / "killed" / JOURNAL_NAME).ok_records()) == QUICK


def test_resuming_with_a_form_that_does_not_make_a_setup_says_why(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "killed")
    with open_run(calibrate.form.setup()) as run:
        for event in run.events():
            if isinstance(event, PatchMeasured) and event.done == 2:
                run.cancel()
    window.ask_resume = lambda journal: True
    form = calibrate.form
    form.display.setCurrentIndex(form.display.findData("tcp"))
    form.tcp.setText("no port here")
    with qtbot.waitSignal(window.error, timeout=RUN_TIMEOUT_MS) as error:
        window.open_path(tmp_path / "killed")
    assert "cannot resume" in error.args[0] and "HOST:PORT" in error.args[0]
    assert not calibrate.running


@pytest.mark.skipif(not REAL.is_dir(), reason=f"the shared real display data is not at {REAL}")
def test_opening_a_real_ti3_shows_its_diagnosis_and_remembers_it(qtbot, window, tmp_path):
    path = REAL / "dell-up2516d-displaycal.ti3"
    with qtbot.waitSignal(window.file_loaded, timeout=RUN_TIMEOUT_MS):
        window.open_path(path)
    diagnose = window.pages["diagnose"]
    diagnose.finish_drawing()
    assert window.current_page_key() == "diagnose"
    assert diagnose.table.rowCount() == 108
    assert "dell-up2516d-displaycal.ti3" in window.windowTitle()
    effects = {card.card.effect for card in diagnose.cards.cards}
    assert effects == {f["effect"] for f in window.workspace.diagnosis.to_json()["findings"]}
    assert window.settings.recent_files() == [str(path.resolve())]
    assert window.settings.path.is_relative_to(tmp_path)
    assert [a.text() for a in window.recent_menu.actions()] == [str(path.resolve())]


def test_a_file_that_cannot_be_read_is_reported_naming_it(qtbot, window, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("kind,r,g\nwhite,1,2\n")
    with qtbot.waitSignal(window.error, timeout=RUN_TIMEOUT_MS) as error:
        window.open_path(bad)
    assert "bad.csv" in error.args[0]


def test_a_view_failing_on_an_opened_file_is_reported_not_raised(qtbot, window, tmp_path, monkeypatch):
    from workbench.gui import main_window
    from workbench.workspace import LoadedPath

    path = tmp_path / "session.csv"
    monkeypatch.setattr(main_window, "load_path", lambda p: LoadedPath(Path(p), None, None))

    def broken_view(workspace):
        raise RuntimeError("the view broke")

    window.workspace.subscribe("session-changed", broken_view)
    with qtbot.waitSignal(window.error, timeout=RUN_TIMEOUT_MS) as error:
        window.open_path(path)
    assert "session.csv" in error.args[0] and "RuntimeError: the view broke" in error.args[0]
    assert window.settings.recent_files() == []


def test_the_flow_has_every_page_in_order_and_a_missing_one_says_why(window):
    assert [window.stack.widget(i).title for i in range(window.stack.count())] == [p[3] for p in PAGES]
    page = _make_page("workbench.gui.pages.no_such_page", "NoPage", "Nowhere", window.workspace)
    assert isinstance(page, UnavailablePage) and page.text().startswith("page not available: ")


def test_the_plan_list_offers_every_built_in_plan_with_its_patch_count(window):
    from workbench.measurement.plans import MEASUREMENT_PLANS, measurement_plan

    form = window.pages["calibrate"].form
    for name in MEASUREMENT_PLANS:
        assert form.plan.findData(name) >= 0, name
    form.plan.setCurrentIndex(form.plan.findData("authors-2024"))
    count = len(measurement_plan("authors-2024", 0))
    assert f"{count} patches" in form.plan.currentText() and "authors" in form.plan.currentText()
    assert f"{count} patches" in form.estimate.text()


def test_the_log_dock_shows_instrument_traffic_at_debug_on_demand(qtbot, window):
    dock = window.log_dock
    logging.getLogger("instruments.cs2000").debug("-> MEAS,1 (before)")
    dock.traffic.setChecked(True)
    logging.getLogger("instruments.cs2000").debug("-> MEAS,1 (after)")
    qtbot.waitUntil(lambda: "(after)" in dock.text.toPlainText(), timeout=2000)
    assert "(before)" not in dock.text.toPlainText()
    dock.traffic.setChecked(False)
    assert logging.getLogger("instruments.cs2000").getEffectiveLevel() > logging.DEBUG


def test_the_tcp_connection_test_names_the_display_or_says_why_not(qtbot, window):
    from instruments.headset import SimulatedHeadset
    from instruments.patch_server import PatchServer

    form = window.pages["calibrate"].form
    form.display.setCurrentIndex(form.display.findData("tcp"))
    with PatchServer(SimulatedHeadset().show, display_name="test headset", idle_timeout_s=5.0) as server:
        server.start()
        host, port = server.address
        form.tcp.setText(f"{host}:{port}")
        _click(qtbot, form.test_tcp)
        qtbot.waitUntil(lambda: "connected: test headset" in form.tcp_status.text(), timeout=10_000)
    form.tcp.setText(f"{host}:{port}")  # the server is gone now
    _click(qtbot, form.test_tcp)
    qtbot.waitUntil(lambda: "cannot connect" in form.tcp_status.text(), timeout=10_000)
    form.tcp.setText("no-port-here")
    _click(qtbot, form.test_tcp)
    assert "is not HOST:PORT" in form.tcp_status.text()
    form.stop_workers()


def test_a_calibration_in_the_full_screen_patch_window_closes_it_at_the_end(qtbot, window, tmp_path):
    calibrate = _configure(window, tmp_path / "run")
    form = calibrate.form
    form.display.setCurrentIndex(form.display.findData("window"))
    form.screen.setCurrentIndex(0)
    assert window.display_label.text() == "patch display: full-screen window on screen 0"
    with qtbot.waitSignal(calibrate.session_loaded, timeout=RUN_TIMEOUT_MS):
        _click(qtbot, calibrate.start_button)
    assert calibrate._patch_window is None
    journal = read_journal(tmp_path / "run" / JOURNAL_NAME)
    assert "patch window" in journal.header.display and len(journal.ok_records()) == QUICK


def test_identify_screens_numbers_every_screen_then_clears(qtbot, window):
    from PySide6.QtGui import QGuiApplication

    from workbench.gui.screen_overlay import identify_screens

    shown = identify_screens(window, show_ms=100)
    assert [w.index for w in shown] == list(range(len(QGuiApplication.screens())))
    assert all(w.isVisible() for w in shown) and shown[0].text.startswith("0\n")
    qtbot.waitUntil(lambda: not any(w.isVisible() for w in shown), timeout=5000)


def test_the_layout_is_remembered_in_the_config_folder(qtbot, tmp_path):
    settings = WindowSettings(tmp_path / "config")
    first = MainWindow(Workspace(), settings)
    first.show()
    qtbot.waitExposed(first)
    assert not first.log_dock.isVisible()
    first.log_dock.show()
    _dispose(first)
    assert settings.path.is_file() and settings.path.is_relative_to(tmp_path)
    second = MainWindow(Workspace(), WindowSettings(tmp_path / "config"))
    second.show()
    qtbot.waitExposed(second)
    assert second.log_dock.isVisible()  # the dock layout came back
    _dispose(second)


@pytest.mark.slow
def test_gui_screenshot_renders_every_page_after_a_simulated_calibration(tmp_path):
    import subprocess
    import sys

    from PIL import Image

    result = subprocess.run([sys.executable, "-m", "workbench", "gui", "--screenshot", str(tmp_path / "shots"),
                             "--simulate"], capture_output=True, text=True, timeout=300,
                            env={**os.environ, "VR_WORKBENCH_CONFIG_DIR": str(tmp_path / "config")})
    assert result.returncode == 0, result.stderr[-2000:]
    for key, *_ in PAGES:
        image = Image.open(tmp_path / "shots" / f"{key}.png")
        assert image.width >= 800 and image.height >= 500
        grey = np.asarray(image.convert("L").resize((64, 40)))
        assert len(np.unique(grey)) > 8  # not one flat colour


def test_the_gui_and_bench_gui_commands_are_registered():
    from workbench.cli import build_parser

    parser = build_parser()
    args = parser.parse_args(["gui", "--simulate", "--screenshot", "out", "session.csv"])
    assert (args.simulate, args.screenshot, args.file) == (True, "out", "session.csv")
    args = parser.parse_args(["bench", "gui", "--json", "--plan", "paper"])
    assert args.json and args.plan == "paper" and args.time_scale == 0.01
