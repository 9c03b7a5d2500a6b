"""Calibrate: set up and run a guided calibration, watch it measure, re-measure what failed.

The run itself is a :class:`~workbench.gui.workers.MeasurementWorker` (the
runner's event generator in a ``QThread``); this page only shows its events:
the patch being measured as a split swatch (nominal DAC colour beside what
the current profile predicts for it, then what was measured), its DAC values
and the instrument's countdown, a progress bar with the runner's ETA (which
knows dark patches are slow), the live sweep and white-reference plots, and
the table of patches (failures with their reason; re-measure any of them).
When a run finishes, the session is read and diagnosed off the GUI thread and
put into the workspace, which fills the other pages.

With the adaptive plan the page shows the plan growing as the planner decides
(:class:`~workbench.measurement.adaptive.PlanState`, sent by the worker after
each step): the patches planned so far and how many the planner chose, the
latest decision's reason as the journal records it, the predicted held-out
ΔE00 and the instrument time left in the budget; the table gets a row for each
patch chosen, and at the end the held-out score on the validation colours with
its 95 % confidence interval
(:func:`~workbench.measurement.adaptive.held_out_summary`).

With the headset's browser (WebXR) as the patch display, the run uses the
window's WebXR server (:class:`~workbench.gui.headset_browser.HeadsetBrowser`,
shared with the Scene page) and waits until the page is in VR; Cancel stops the wait.

:meth:`CalibratePage.measure_follow_up` measures a follow-up plan (the Fit &
diagnose page's "Measure the N patches that identify this") into the
finished session's directory with the session's setup, as ``measure
--add-plan`` does; a session without a measurement directory gets the plan
file put into the form (plan "from a file…") for a new session instead.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
from PySide6.QtCore import QEventLoop, Qt, Signal
from PySide6.QtWidgets import (
    QApplication,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QPushButton,
    QScrollArea,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gui.calibration_setup import SIMULATED, CalibrationSetup, planned
from workbench.gui.diagnosis_views import XYZ_to_srgb8
from workbench.gui.headset_browser import HeadsetBrowser
from workbench.gui.measure_window import WorkerPatchDisplay
from workbench.gui.widgets.calibration_form import CalibrationForm
from workbench.gui.widgets.headset_panel import HeadsetPanel
from workbench.gui.widgets.measurement_plots import MeasurementPlots
from workbench.gui.widgets.patch_swatch import SplitSwatch
from workbench.gui.widgets.patch_table import PatchTable
from workbench.gui.workers import CallWorker, MeasurementWorker, describe_error
from workbench.measurement.adaptive import held_out_summary
from workbench.measurement.runner import (
    PatchMeasured,
    PatchStarted,
    RunFinished,
    RunPaused,
    RunResumed,
    RunStarted,
    format_duration,
)
from workbench.workspace import load_path, unfinished_journal

__all__ = ["CalibratePage"]

_LOG = logging.getLogger(__name__)

_FORM_WIDTH = 440
"""Pixels: the setup form's column where the window is wide enough (its lists show whole at 1366 × 768)."""

_FORM_MIN_WIDTH = 300
"""Pixels: the least width of the setup form's column (the form fits it without scrolling sideways)."""


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


class CalibratePage(QWidget):
    """The guided calibration.

    Attributes
    ----------
    run_finished(object)
        The run's :class:`~workbench.measurement.runner.RunSummary`.
    session_loaded()
        The finished session was read, diagnosed and put into the workspace.
    error(str)
        A run could not start or stopped; the message says what to do.
    """

    title = "Calibrate"
    run_finished = Signal(object)
    session_loaded = Signal()
    error = Signal(str)

    def __init__(self, workspace, parent=None):
        super().__init__(parent)
        self.workspace = workspace
        self.worker: MeasurementWorker | None = None
        self._loaders: list = []
        self._patch_window = None
        self._white_XYZ = None
        self._setup: CalibrationSetup | None = None
        self._active = False
        self._core_size = 0
        self._adaptive_run = False
        self.plan_state = None
        """The adaptive plan's latest :class:`~workbench.measurement.adaptive.PlanState` (None: not adaptive)."""

        self.form = CalibrationForm()
        self.headset = HeadsetPanel(inline_qr=True, qr_px=110)
        self.headset.setMinimumWidth(300)  # the state's words beside the QR code, not a column of them
        self.headset.setMaximumWidth(420)
        self._own_headset = HeadsetBrowser(self)  # until the window gives its shared one
        self.headset_browser = self._own_headset
        self.headset.bind(self._own_headset)
        self.form.bind_headset_browser(self._own_headset)
        # The form follows the column's width (it wraps and elides rather than widening): vertical
        # scrolling only, as on a 1366 × 768 screen.
        self.form_scroll = form_scroll = QScrollArea()
        form_scroll.setWidget(self.form)
        form_scroll.setWidgetResizable(True)
        form_scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        form_scroll.setMinimumWidth(_FORM_MIN_WIDTH)

        self.start_button = QPushButton("Start")
        self.pause_button = QPushButton("Pause")
        self.cancel_button = QPushButton("Cancel")
        self.start_button.setToolTip("start the calibration (Ctrl+R); a journal in the output directory is resumed")
        buttons = QHBoxLayout()
        for button in (self.start_button, self.pause_button, self.cancel_button):
            buttons.addWidget(button)
        self.swatch = SplitSwatch()
        self.patch_label = QLabel("no patch yet")
        self.patch_label.setWordWrap(True)  # a long line (a run's summary) wraps rather than widening the column
        self.countdown_label = QLabel("")
        self.progress = QProgressBar()
        self.progress.setFormat("%v of %m patches")
        self.eta_label = QLabel("")
        self.plan_label = QLabel("")
        self.plan_label.setWordWrap(True)
        self.plan_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.plan_label.setVisible(False)
        self.message = QLabel("")
        self.message.setWordWrap(True)
        self.message.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.plots = MeasurementPlots()
        self.patches = PatchTable()

        status = QVBoxLayout()
        status.addLayout(buttons)
        status.addWidget(self.patch_label)
        status.addWidget(self.countdown_label)
        status.addWidget(self.progress)
        status.addWidget(self.eta_label)
        status.addWidget(self.message)
        top = QHBoxLayout()
        top.addWidget(self.swatch, 1)
        top.addLayout(status, 1)
        top.addWidget(self.headset, 0)  # the headset's browser: URL, QR code, page state
        right = QSplitter(Qt.Orientation.Vertical)
        top_widget = QWidget()
        column = QVBoxLayout(top_widget)
        column.setContentsMargins(0, 0, 0, 0)
        column.addLayout(top, 1)
        column.addWidget(self.plan_label)  # the adaptive plan: under both, as wide as the page
        self._right, self._top_widget, self._top_row = right, top_widget, top
        right.addWidget(top_widget)
        right.addWidget(self.plots)
        right.addWidget(self.patches)
        right.setSizes([180, 320, 260])
        splitter = QSplitter()
        splitter.addWidget(form_scroll)
        splitter.addWidget(right)
        splitter.setSizes([_FORM_WIDTH, 1060])
        splitter.setStretchFactor(0, 0)  # a narrower window narrows the plots, not the form
        splitter.setStretchFactor(1, 1)
        layout = QHBoxLayout(self)
        layout.addWidget(splitter)

        self.start_button.clicked.connect(lambda: self.start())
        self.pause_button.clicked.connect(self.toggle_pause)
        self.cancel_button.clicked.connect(self.cancel)
        self.patches.remeasure.connect(self.remeasure)
        self.form.changed.connect(self._update_start_label)
        self.form.display.currentIndexChanged.connect(self._show_headset_panel)
        self._show_headset_panel()
        self._set_running(False)
        self._update_start_label()

    def use_headset_browser(self, service: HeadsetBrowser) -> None:
        """Show the patches in the headset's browser through ``service`` (the window's, shared)."""
        if service is self.headset_browser:
            return
        self.headset_browser = service
        self.headset.bind(service)
        self.form.bind_headset_browser(service)
        if self._own_headset is not None:
            self._own_headset.shutdown()
            self._own_headset = None

    def _show_headset_panel(self) -> None:
        """The headset's browser's URL, QR code and state show while it is the patch display."""
        self.headset.setVisible(self.form.display.currentData() == "webxr")

    # -- controls -----------------------------------------------------------------------
    @property
    def running(self) -> bool:
        """Whether a run is going: from :meth:`start` until the page has handled its worker's end."""
        return self._active

    def _update_start_label(self) -> None:
        try:
            journal = unfinished_journal(self.form.setup().out_dir)
        except WorkbenchError:
            journal = None
        self.start_button.setText("Resume" if journal is not None else "Start")

    def _set_running(self, running: bool) -> None:
        self.start_button.setEnabled(not running)
        self.pause_button.setEnabled(running)
        self.cancel_button.setEnabled(running)
        self.form.setEnabled(not running)
        self.patches.set_idle(not running)
        if not running:
            self.pause_button.setText("Pause")

    def start(self, setup: CalibrationSetup | None = None) -> None:
        """Start (or resume) the calibration the form describes, or ``setup``."""
        if self.running:
            return
        try:
            setup = setup or self.form.setup()
            plan, journal = planned(setup)
            webxr_server = self._webxr_server(setup) if setup.display == "webxr" else None
            window_display = self._open_patch_window(setup) if setup.display == "window" else None
        except WorkbenchError as error:
            self._show_error(str(error))
            return
        self._setup = setup
        self.message.setText("")
        self.plots.clear()
        self.patches.set_plan(plan, journal)
        self._white_XYZ = None
        if journal is not None:
            for record in journal.latest().values():
                self._record_point(record)
        self.progress.setRange(0, len(plan))
        self.progress.setValue(0 if journal is None else sum(1 for r in journal.latest().values() if r.ok))
        adaptive = setup.adaptive if journal is None else "adaptive" in journal.header.settings
        self._core_size = len(plan) - sum(len(d.get("patches", ())) for d in journal.decisions) \
            if journal is not None else len(plan)
        self._adaptive_run = bool(adaptive)
        self.plan_state = None
        self.plan_label.setVisible(adaptive)
        self.plan_label.setText("adaptive plan: the core first, then the planner decides after each patch"
                                if adaptive else "")
        self._fit_top()
        if webxr_server is not None:
            self.patch_label.setText("waiting for the headset's browser to enter VR (Cancel stops waiting)")
        self.worker = MeasurementWorker(setup, window_display, self, webxr_server=webxr_server)
        self.worker.event.connect(self._on_event)
        self.worker.countdown.connect(self._on_countdown)
        self.worker.plan_state.connect(self._on_plan_state)
        self.worker.failed.connect(self._on_failed)
        self.worker.finished.connect(self._on_worker_finished)
        self.workspace.set_measurement(status="running", instrument=setup.describe_instrument(),
                                       display=setup.describe_display(), out_dir=setup.out_dir,
                                       done=0, total=len(plan), message="")
        self._active = True
        self._set_running(True)
        self.worker.start()

    def _webxr_server(self, setup: CalibrationSetup):
        """The running WebXR server at the setup's address (started if it is not)."""
        service = self.headset_browser
        server = service.server
        if server is None or (server.host, server.port) != tuple(setup.webxr_address):
            host, port = setup.webxr_address
            server = service.start(host, port)
        return server

    def _open_patch_window(self, setup: CalibrationSetup):
        from workbench.gui.patch_window import PatchWindow, QtPatchDisplay

        screen = setup.screen
        if screen is None:
            from PySide6.QtGui import QGuiApplication

            screen = len(QGuiApplication.screens()) - 1
        self._patch_window = PatchWindow(screen)
        return WorkerPatchDisplay(QtPatchDisplay(self._patch_window, 10.0))

    def toggle_pause(self) -> None:
        if not self.running or self.worker is None:
            return
        if self.pause_button.text() == "Pause":
            self.worker.pause()
            self.pause_button.setText("Resume")
            self.patch_label.setText(self.patch_label.text() + " — pausing after this patch")
        else:
            self.worker.resume()
            self.pause_button.setText("Pause")

    def cancel(self) -> None:
        if self.running and self.worker is not None:
            self.worker.cancel()

    def remeasure(self, indices: list) -> None:
        """Measure these plan indices again (resuming the session in the same output directory)."""
        if self.running or not indices:
            return
        base = self._setup or self.form.setup()
        self.start(replace(base, remeasure=tuple(int(i) for i in indices), add_plan=None))

    def measure_follow_up(self, plan_path, out_dir=None) -> str:
        """Measure the plan file ``plan_path`` into the finished session in ``out_dir``.

        The setup is the form's with the session's own instrument kind
        (simulated or not; a simulation's effects come from its journal) and,
        for a simulated session shown on the simulated headset, that display:
        the follow-up must be shown as the session was (the runner refuses
        another display, naming both). Without ``out_dir`` (the session has no
        measurement directory) the plan file is put into the form as a new
        session's plan, and nothing starts. Returns ``"started"``,
        ``"prefilled"`` or ``"refused"`` (the message says why).
        """
        from workbench.measurement.journal import read_journal
        from workbench.measurement.runner import JOURNAL_NAME

        if out_dir is None:
            self.form.plan_file.setText(str(plan_path))
            self.form.plan.setCurrentIndex(self.form.plan.findData("file"))
            self.message.setText(f"The follow-up plan {plan_path} is set as this calibration's plan file: the "
                                 "open session has no measurement directory to add it to, so it is measured "
                                 "as a new session. Check the instrument, the display and the output "
                                 "directory, then Start.")
            return "prefilled"
        if self.running:
            self._show_error("a calibration is running: measure the follow-up when it has ended")
            return "refused"
        try:
            journal = read_journal(f"{out_dir}/{JOURNAL_NAME}")
            simulated = bool(journal.header.settings.get("simulated"))
            changes = dict(out_dir=out_dir, add_plan=plan_path, effects={},
                           instrument=SIMULATED if simulated else self.form.instrument.currentData())
            if simulated and " + " not in journal.header.display:  # shown on the simulated headset alone
                changes["display"] = "simulated"
            elif not simulated and self.form.instrument.currentData() == SIMULATED:
                changes["instrument"] = "auto"
            setup = self.form.setup(**changes)
        except WorkbenchError as error:
            self._show_error(f"cannot measure the follow-up: {error}")
            return "refused"
        self.form.out_dir.setText(str(out_dir))
        self.start(setup)
        return "started" if self.running else "refused"

    def stop(self) -> None:
        """Cancel a run and wait for every worker (teardown)."""
        if self.worker is not None:
            self.worker.cancel()
            self.worker.wait()
        for loader in list(self._loaders):
            loader.wait()
        self.form.stop_workers()
        self._close_patch_window()
        if self._own_headset is not None:
            self._own_headset.shutdown()

    # -- events ---------------------------------------------------------------------------
    def _on_event(self, event) -> None:
        if isinstance(event, RunStarted):
            self.progress.setValue(event.done)
        elif isinstance(event, PatchStarted):
            self._patch_started(event)
        elif isinstance(event, PatchMeasured):
            self._patch_measured(event)
        elif isinstance(event, RunPaused):
            self.patch_label.setText(f"paused before patch #{event.next_index} ({event.done} of {event.total} done)")
            self.workspace.set_measurement(status="paused")
        elif isinstance(event, RunResumed):
            self.workspace.set_measurement(status="running")
        elif isinstance(event, RunFinished):
            self._run_finished(event.summary)

    def _patch_started(self, event: PatchStarted) -> None:
        if event.total != self.progress.maximum():  # a dynamic plan has grown
            self.progress.setMaximum(event.total)
            self.workspace.set_measurement(total=event.total)
        self.patches.add_patch(event.index, event.patch)
        rgb = event.patch.rgb
        self.patch_label.setText(f"<b>#{event.index}</b> {event.patch.kind} — DAC {rgb[0]}, {rgb[1]}, {rgb[2]}")
        self.countdown_label.setText("")
        self.patches.set_measuring(event.index)
        model = self.workspace.profile.display_model()
        predicted = XYZ_to_srgb8(model.forward(np.array([rgb], dtype=float))[0], model.white_XYZ)
        self.swatch.set_colours(rgb, predicted, "predicted by the current profile")
        self._show_eta(event.eta_s)

    def _patch_measured(self, event: PatchMeasured) -> None:
        record = event.record
        self.patches.set_record(record)
        self.progress.setValue(event.done)
        self._show_eta(event.eta_s)
        self.workspace.set_measurement(done=event.done)
        if record.ok:
            self._record_point(record)
            white = self._white_XYZ if self._white_XYZ is not None else \
                self.workspace.profile.display_model().white_XYZ
            self.swatch.set_colours(record.rgb, XYZ_to_srgb8(np.array(record.XYZ), white), "measured")
        else:
            self.swatch.set_colours(record.rgb, None, "failed")
            self.message.setText(f"<span style='color:#b03a2e'>patch #{record.index} failed: {record.reason}. "
                                 "It is listed below; re-measure it when the run ends.</span>")

    def _record_point(self, record) -> None:
        if record.ok and record.kind == "white":
            self._white_XYZ = np.array(record.XYZ)
        self.plots.add(record)

    def _show_eta(self, eta_s) -> None:
        self.eta_label.setText("" if eta_s is None else f"about {format_duration(eta_s)} left")

    def _on_plan_state(self, state) -> None:
        """Show the adaptive plan as it grows (a :class:`~workbench.measurement.adaptive.PlanState`)."""
        chosen = state.planned - self._core_size
        decisions = len(state.decisions)
        parts = [f"<b>adaptive plan: {state.planned} patches so far</b> ({self._core_size} in the core, "
                 f"{chosen} chosen by {decisions} decision{'s' if decisions != 1 else ''}; "
                 f"{state.measured} measured)"]
        if state.predicted_dE00 is not None:
            parts.append(f"predicted held-out ΔE00 <b>{state.predicted_dE00:.3f}</b>")
        if state.time_left_s is not None:
            parts.append(f"budget left <b>{format_duration(state.time_left_s)}</b> of "
                         f"{format_duration(state.budget_s)} (instrument time)")
        text = "; ".join(parts)
        if state.decisions:
            last = state.decisions[-1]
            text += f"<br>decision {last.get('number', decisions)}: {_escape(str(last.get('reason', '')))}"
        if state.stopped:
            text += ("<br>the planner has stopped: measuring the validation colours" if state.measured
                     < state.planned else "<br>the planner stopped, and the validation colours are measured")
        self.plan_label.setVisible(True)
        self.plan_label.setText(text)
        self.plan_state = state
        self._fit_top()

    def _fit_top(self) -> None:
        """Make the pane above the plots tall enough for the adaptive plan's lines (from the table's and
        the plots' heights), so that none is cut off."""
        if not self.plan_label.isVisible():
            return
        QApplication.processEvents(QEventLoop.ProcessEventsFlag.ExcludeUserInputEvents)  # the label's width
        width = self.plan_label.width() or self._top_widget.width()
        need = (self._top_row.minimumSize().height() + self.plan_label.heightForWidth(width)
                + 2 * self._top_widget.layout().spacing() + 8)
        sizes = self._right.sizes()
        short = need - sizes[0]
        if short <= 0 or len(sizes) < 3:
            return
        take_table = min(short, max(sizes[2] - 120, 0))
        take_plots = min(short - take_table, max(sizes[1] - 200, 0))
        self._right.setSizes([sizes[0] + take_table + take_plots, sizes[1] - take_plots, sizes[2] - take_table])

    def _on_countdown(self, remaining_s: float, total_s: float) -> None:
        self.countdown_label.setText(f"instrument: {remaining_s:.0f} s left of {total_s:.0f} s")

    def _on_failed(self, message: str) -> None:
        if self.worker is not None and self.worker.cancelled and self.worker.setup.display == "webxr":
            # cancelled while waiting for the headset's browser: nothing was measured
            self.workspace.set_measurement(status="cancelled", message=message)
            self.patch_label.setText("cancelled before the first patch (the headset's page was not in VR)")
            _LOG.info("%s", message)
            return
        self.workspace.set_measurement(status="aborted", message=message)
        self._show_error(message)

    def _show_error(self, message: str) -> None:
        self.message.setText(f"<span style='color:#b03a2e'><b>error:</b> {message}</span>")
        _LOG.error("%s", message)
        self.error.emit(message)

    def _run_finished(self, summary) -> None:
        self.workspace.set_measurement(status=summary.status, done=summary.measured)
        self.patch_label.setText(summary.one_line("simulated" if self._setup.simulated else "session"))
        self.countdown_label.setText("")
        self.eta_label.setText("")
        self.run_finished.emit(summary)
        if summary.status == "finished":
            self._load_session()

    def _on_worker_finished(self) -> None:
        self._active = False
        self._close_patch_window()
        self._set_running(False)
        self._update_start_label()

    def _close_patch_window(self) -> None:
        if self._patch_window is not None:
            self._patch_window.close()
            self._patch_window = None

    def _load_session(self) -> None:
        """Read and diagnose the finished session off the GUI thread, then put it into the workspace."""
        out_dir = self._setup.out_dir
        adaptive = self._adaptive_run

        def load():
            return load_path(out_dir), (held_out_summary(out_dir) if adaptive else None)

        loader = CallWorker(load, self)
        loader.done.connect(self._session_loaded)
        loader.failed.connect(lambda message: self._show_error(f"the session could not be diagnosed: {message}"))
        loader.finished.connect(lambda: self._loaders.remove(loader))
        self._loaders.append(loader)
        loader.start()

    def _session_loaded(self, result) -> None:
        loaded, held_out = result
        if held_out:
            self.plan_label.setText(self.plan_label.text() + f"<br><b>{_escape(held_out)}</b>")
            self._fit_top()
        try:
            self.workspace.apply(loaded)
        except Exception as error:  # noqa: BLE001 - a view failing must reach the user
            self._show_error(describe_error(error))
            return
        self.session_loaded.emit()
