"""Fit & diagnose: what the diagnosis of the open session found, and how the models fit.

Shows whatever :func:`workbench.diagnostics.diagnose` returned (through
:mod:`workbench.gui.diagnosis_views`): the verdict (every top-level entry of
``to_json()``; the effects checked and not found, or not testable, as a table:
effect, z against the critical value, statistic ± SE, impact, in the model or
why not, the evidence in the row's tooltip; "Other entries" shows the rest of
``to_json()`` in its place), the model the profile exports (a table of the
candidates' cross-validated ΔE00, the chosen one marked, and why), the findings as cards
with their evidence and a plot each (a consequence of another finding
indented under its cause, tagged "consequence of …"), per-channel sweep fits
with residuals (baseline vs extended), additivity, chromaticity vs drive, the
white references over time, the validation table and the ΔE00 histograms.
"Open report" writes the HTML report and opens it. Every text wraps; the page
fits a 1366 × 768 screen.

Where the diagnosis leaves something a measurement would identify, the card
of that finding carries "Measure the N patches that identify this — about M
min" (the proposal is :func:`workbench.diagnostics.follow_up.propose_follow_up`'s):
it writes the follow-up as a plan file and asks (``follow_up_requested``) for
it to be measured — into the session's measurement directory with the same
setup where the session has one, else as a new session from the plan file.
"""

from __future__ import annotations

import html
import logging
import tempfile
from pathlib import Path

from PySide6.QtCore import QTimer, QUrl, Qt, Signal
from PySide6.QtGui import QDesktopServices
from PySide6.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSizePolicy,
    QSplitter,
    QStackedWidget,
    QTextBrowser,
    QVBoxLayout,
    QWidget,
)

from workbench.gui import diagnosis_views as views
from workbench.gui.widgets.checked_table import CheckedTable
from workbench.gui.widgets.finding_cards import FindingCards
from workbench.gui.widgets.fit_plots import FitPlots
from workbench.gui.widgets.validation_table import ValidationHistogram, ValidationTable

__all__ = ["DiagnosePage"]

_LOG = logging.getLogger(__name__)

STEP_INTERVAL_MS = 1
"""Milliseconds between two parts of a diagnosis drawn (:meth:`DiagnosePage._next_step`)."""

_DONE = object()

_BOTTOM_PLOT_MIN_WIDTH = 160
"""Pixels: the least width of each plot in the row below the sweeps (the page fits 1366 × 768)."""


class DiagnosePage(QWidget):
    """The diagnosis of the workspace's session; updates on ``diagnosis-changed``.

    Attributes
    ----------
    follow_up_requested(object, object)
        The follow-up's plan file (a Path) and the measurement directory to
        measure it into (a Path), or None where the session has none.
    """

    title = "Fit & diagnose"
    follow_up_requested = Signal(object, object)

    def __init__(self, workspace, parent=None):
        super().__init__(parent)
        self.workspace = workspace
        self.summary = QLabel("")
        self.summary.setWordWrap(True)
        self.summary.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        # What was checked and not found is a table; everything else the diagnosis returned is one
        # click away, in the table's place and as high (it scrolls).
        self.checked = CheckedTable()
        self.details = QTextBrowser()
        self.details.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Ignored)
        self.details.setToolTip("everything else the diagnosis returned")
        self.checked_stack = QStackedWidget()
        self.checked_stack.addWidget(self.checked)
        self.checked_stack.addWidget(self.details)
        self.checked_stack.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Maximum)
        self.details_button = QPushButton("Other entries")
        self.details_button.setCheckable(True)
        self.details_button.setToolTip("show everything else the diagnosis returned in place of the table of the "
                                       "effects checked and not found (click again for the table)")
        self.details_button.toggled.connect(lambda shown: self.checked_stack.setCurrentIndex(int(shown)))
        self.report_button = QPushButton("Open report")
        self.report_button.setToolTip("write the HTML report of this diagnosis and open it in the browser")
        self.report_button.clicked.connect(self.open_report)
        self.report_path: Path | None = None
        self.follow_up = None
        self._drawing = None  # the parts of the shown diagnosis not drawn yet (a generator)
        # the page's own timer: it stops with the page, so no step outlives the widgets it draws
        self._step_timer = QTimer(self)
        self._step_timer.setSingleShot(True)
        self._step_timer.setInterval(STEP_INTERVAL_MS)
        self._step_timer.timeout.connect(self._next_step)
        self.cards = FindingCards()
        self.fits = FitPlots()
        # Four plots share the row below the sweeps where the session has greys: at their default
        # minimum width the page was wider than a 1366-pixel screen and clipped the right column.
        for plot in (self.fits.additivity, self.fits.greys, self.fits.chromaticity, self.fits.whites):
            plot.setMinimumWidth(_BOTTOM_PLOT_MIN_WIDTH)
        self.table = ValidationTable()
        self.histogram = ValidationHistogram()

        header = QHBoxLayout()
        header.addWidget(self.summary, 2)
        header.addWidget(self.checked_stack, 3)
        buttons = QVBoxLayout()
        buttons.addWidget(self.report_button)
        buttons.addWidget(self.details_button)
        buttons.addStretch(1)
        header.addLayout(buttons)
        right = QSplitter(Qt.Orientation.Vertical)
        right.addWidget(self.table)
        right.addWidget(self.histogram)
        right.setSizes([500, 260])
        splitter = QSplitter()
        splitter.addWidget(self.cards)
        splitter.addWidget(self.fits)
        splitter.addWidget(right)
        splitter.setSizes([360, 900, 420])
        layout = QVBoxLayout(self)
        layout.addLayout(header)
        layout.addWidget(splitter, 1)
        workspace.subscribe("diagnosis-changed", lambda ws: self.show_diagnosis(ws.diagnosis))
        self.show_diagnosis(workspace.diagnosis)

    def show_diagnosis(self, diagnosis) -> None:
        self.report_button.setEnabled(diagnosis is not None)
        self.report_path = None
        if diagnosis is None:
            self.summary.setText("<i>No diagnosis yet: run a calibration, or open a session CSV, .ti3, .mat, "
                                 "measurement directory or profile (File ▸ Open).</i>")
            self.details.setHtml("")
            details = ()
        else:
            self.summary.setText("<br>".join(f"<b>{key}</b>: {text}" for key, text in views.summary_lines(diagnosis)))
            details = tuple((key, text) for key, text in views.detail_lines(diagnosis)
                            if key not in views.CHECKED_KEYS)
            self.details.setHtml("<br>".join(f"<b>{key}</b>: {html.escape(text)}" for key, text in details))
        self.checked.show_diagnosis(diagnosis)
        self.details_button.setText(f"Other entries ({len(details)})")
        self.follow_up = None
        self._drawing = self._drawing_steps(diagnosis)
        self._next_step()

    def _drawing_steps(self, diagnosis):
        """The page's parts for ``diagnosis``, one per step (:meth:`_next_step`)."""
        self.table.show_diagnosis(diagnosis)
        yield
        self.histogram.show_diagnosis(diagnosis)
        yield
        yield from self.fits.drawing_steps(diagnosis)
        yield
        self._show_follow_up(diagnosis)  # planning it is 14 ms on the paper plan
        yield
        yield from self.cards.drawing_steps(diagnosis)

    def _show_follow_up(self, diagnosis) -> None:
        """Plan the follow-up of ``diagnosis`` and offer it on the finding it serves."""
        self.follow_up = follow_up = self._propose(diagnosis)
        if follow_up is not None and follow_up.patches:
            self.cards.set_action(follow_up.serves, follow_up.headline(), "\n".join(follow_up.lines()),
                                  self.measure_follow_up)
        else:
            self.cards.set_action(None, "", "", None)

    @staticmethod
    def _propose(diagnosis):
        """The follow-up of ``diagnosis`` (None without one, or where it cannot be proposed)."""
        if diagnosis is None:
            return None
        from workbench.diagnostics.follow_up import propose_follow_up

        try:
            return propose_follow_up(diagnosis)
        except Exception:  # noqa: BLE001 - the page still shows the diagnosis without the button
            _LOG.warning("no follow-up could be proposed for this diagnosis", exc_info=True)
            return None

    def measure_follow_up(self) -> tuple:
        """Write the follow-up plan file and ask for it to be measured; returns ``(plan file, directory)``."""
        from workbench.workspace import write_follow_up_plan

        if self.follow_up is None or not self.follow_up.patches:
            return None, None
        path, directory = write_follow_up_plan(self.follow_up, self.workspace.session_path)
        _LOG.info("follow-up plan %s: %s", path, self.follow_up.summary())
        self.follow_up_requested.emit(path, directory)
        return path, directory

    def _next_step(self) -> None:
        """Draw the next part of the diagnosis shown, and the one after it on a timer.

        A part is a plot, a finding card or a table (tens of milliseconds each, and as much again
        to repaint). On a timer of :data:`STEP_INTERVAL_MS`, not a zero timer: Qt runs a zero
        timer as a posted event, the event loop serves posted events (the repaints among them)
        until none is left before it serves a timer, and a chain of zero timers held the window
        as one stall: after a paper-plan run no 10 ms timer fired for 566 ms while six parts
        were drawn. On a 1 ms timer, a part a plot, the longest wait after the run was 98–116 ms
        in three runs, where the page is shown with its tables; every later part's under 100 ms.
        """
        self._step_timer.stop()  # a new diagnosis: its first part now, the rest on the timer
        if self._drawing is None:
            return
        if next(self._drawing, _DONE) is _DONE:
            self._drawing = None
            return
        self._step_timer.start()

    def finish_drawing(self) -> None:
        """Draw every part still waiting for its event-loop turn (tests, screenshots)."""
        self._step_timer.stop()
        if self._drawing is not None:
            for _ in self._drawing:
                pass
            self._drawing = None

    def write_report(self, path=None) -> Path:
        """Write the HTML report of the current diagnosis (a temporary file by default)."""
        from workbench.diagnostics.report import write_report

        if path is None:
            name = Path(self.workspace.diagnosis.session.source).stem or "session"
            path = Path(tempfile.gettempdir()) / f"vr-workbench-report-{name}.html"
        self.report_path = write_report(self.workspace.diagnosis, path)
        return self.report_path

    def open_report(self) -> None:
        if self.workspace.diagnosis is None:
            return
        QDesktopServices.openUrl(QUrl.fromLocalFile(str(self.write_report())))
