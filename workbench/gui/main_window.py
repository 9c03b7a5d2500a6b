"""The workbench window: the flow Calibrate → Fit & diagnose → Gamut → Illuminants → Scene → Export.

It only arranges pages (:mod:`workbench.gui.pages`) around one
:class:`~workbench.workspace.Workspace`: a flow bar to move between them, the
File menu (Open accepts everything ``diagnose`` reads; recent files), the
log dock, and a status bar naming the instrument and the patch display. Recent
files and the window layout persist (:class:`~workbench.gui.settings.WindowSettings`).
The window's one WebXR server (:class:`~workbench.gui.headset_browser.HeadsetBrowser`)
is shared by the Calibrate page (patches in the headset's browser) and the
Scene page (the lightbooth in it), and stops when the window closes.

Pages another module provides are imported defensively: a page that cannot be
imported shows why in its place, and the others work.
"""

from __future__ import annotations

import importlib
import logging
from pathlib import Path

from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QButtonGroup,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QMainWindow,
    QMessageBox,
    QStackedWidget,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gui.headset_browser import HeadsetBrowser
from workbench.gui.log_dock import LogDock
from workbench.gui.settings import WindowSettings
from workbench.gui.workers import CallWorker, describe_error
from workbench.workspace import load_path, unfinished_journal

__all__ = ["PAGES", "DEFAULT_SIZE", "MainWindow", "UnavailablePage", "OPEN_FILTER", "SHORTCUTS"]

_LOG = logging.getLogger(__name__)

PAGES = (
    ("calibrate", "workbench.gui.pages.calibrate", "CalibratePage", "Calibrate"),
    ("diagnose", "workbench.gui.pages.diagnose", "DiagnosePage", "Fit & diagnose"),
    ("gamut", "workbench.gui.pages.gamut", "GamutPage", "Gamut"),
    ("illuminants", "workbench.gui.pages.illuminants", "IlluminantsPage", "Illuminants"),
    ("scene", "workbench.gui.pages.scene", "ScenePage", "Scene"),
    ("export", "workbench.gui.pages.export", "ExportPage", "Export"),
)
"""The flow, in order: (key, module, class, title)."""

DEFAULT_SIZE = (1500, 950)
"""The window's size, pixels, until the user's saved layout says otherwise (every page also fits 1366 × 768)."""

OPEN_FILTER = ("Sessions and profiles (*.csv *.ti3 *.mat *.json);;Session CSV (*.csv);;Argyll (*.ti3);;"
               "Psychtoolbox (*.mat);;Profile (*.vrprofile.json *.json);;All files (*)")

SHORTCUTS = (
    ("Ctrl+O", "open a session, .ti3, .mat, measurement directory (Ctrl+Shift+O) or profile"),
    ("Ctrl+1 … Ctrl+6", "go to a step of the flow"),
    ("Ctrl+R", "start or resume the calibration"),
    ("Ctrl+P", "pause / resume the calibration"),
    ("Ctrl+.", "cancel the calibration"),
    ("Ctrl+E", "write the profile"),
    ("Ctrl+L", "show or hide the log"),
    ("Ctrl+Q", "quit"),
)
"""Keyboard shortcuts (the README and Help ▸ Keyboard shortcuts list them)."""


class UnavailablePage(QLabel):
    """Stands in for a page whose module cannot be imported; says why."""

    def __init__(self, title: str, reason: str, parent=None):
        super().__init__(f"page not available: {reason}", parent)
        self.title = title
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setWordWrap(True)


def _make_page(module: str, name: str, title: str, workspace):
    try:
        page_class = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as error:
        _LOG.info("page %s not available: %s", title, error)
        return UnavailablePage(title, f"{type(error).__name__}: {error}")
    return page_class(workspace)


class MainWindow(QMainWindow):
    """The workbench window over ``workspace``.

    Parameters
    ----------
    workspace : Workspace
    settings : WindowSettings, optional
        Where recent files and the layout are kept (tests give a temporary one).
    lazy : bool
        Build only the Calibrate page before the window first paints; the
        others are built one per event-loop turn after it (or at once when
        shown), so that the window appears quickly.

    Attributes
    ----------
    file_loaded(object)
        A file opened with :meth:`open_path` was read, diagnosed and applied.
    error(str)
        Something the user asked for failed; the message says what to do.
    """

    file_loaded = Signal(object)
    error = Signal(str)

    def __init__(self, workspace, settings: WindowSettings | None = None, parent=None, *, lazy: bool = False):
        super().__init__(parent)
        self.workspace = workspace
        self.settings = settings or WindowSettings()
        self.setObjectName("workbench-main-window")
        self.pages: dict = {}
        self._pending: dict = {}
        self._loaders: list = []
        self.headset_browser = HeadsetBrowser(self)
        self.stack = QStackedWidget()
        self.flow = QButtonGroup(self)
        flow_bar = QHBoxLayout()
        flow_bar.setContentsMargins(8, 6, 8, 2)
        for i, (key, module, name, title) in enumerate(PAGES):
            if lazy and key != "calibrate":
                placeholder = QLabel(f"loading {title}…")
                placeholder.setAlignment(Qt.AlignmentFlag.AlignCenter)
                self._pending[key] = placeholder
                self.stack.addWidget(placeholder)
            else:
                page = _make_page(module, name, title, workspace)
                self.pages[key] = page
                self.stack.addWidget(page)
                if key != "calibrate":
                    self._wire(key, page)
            if i:
                arrow = QLabel("→")
                arrow.setStyleSheet("color:#888;font-size:14px")
                flow_bar.addWidget(arrow)
            button = QToolButton()
            button.setText(f"{i + 1}  {title.replace('&', '&&')}")
            button.setCheckable(True)
            button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
            button.setStyleSheet("QToolButton{padding:5px 12px;font-size:13px}"
                                 "QToolButton:checked{background:#2e6fd0;color:white;border-radius:4px}")
            self.flow.addButton(button, i)
            flow_bar.addWidget(button)
        flow_bar.addStretch(1)
        self.flow.idClicked.connect(lambda i: self.show_page(PAGES[i][0]))
        self.stack.currentChanged.connect(lambda i: self.flow.button(i).setChecked(True))
        self.flow.button(0).setChecked(True)
        central = QWidget()
        layout = QVBoxLayout(central)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(flow_bar)
        layout.addWidget(self.stack, 1)
        self.setCentralWidget(central)

        self.log_dock = LogDock(self)
        self.addDockWidget(Qt.DockWidgetArea.BottomDockWidgetArea, self.log_dock)
        self.log_dock.hide()
        self.instrument_label = QLabel("")
        self.display_label = QLabel("")
        self.statusBar().addPermanentWidget(self.instrument_label)
        self.statusBar().addPermanentWidget(self.display_label)
        self._build_menus()

        calibrate = self.pages["calibrate"]
        if hasattr(calibrate, "use_headset_browser"):
            calibrate.use_headset_browser(self.headset_browser)
        calibrate.session_loaded.connect(lambda: self.show_page("diagnose"))
        calibrate.form.changed.connect(self._update_status)
        calibrate.error.connect(self.statusBar().showMessage)
        for event in ("session-changed", "profile-changed"):
            workspace.subscribe(event, lambda ws: self._update_title())
        workspace.subscribe("measurement-changed", lambda ws: self._update_status())
        self._update_title()
        self._update_status()
        self.resize(*DEFAULT_SIZE)
        geometry, state = self.settings.layout()
        if geometry is not None:
            self.restoreGeometry(geometry)
        if state is not None:
            self.restoreState(state)

    # -- menus ----------------------------------------------------------------------------
    def _action(self, menu, text: str, slot, shortcut: str | None = None) -> QAction:
        action = QAction(text, self)
        if shortcut:
            action.setShortcut(QKeySequence(shortcut))
        action.triggered.connect(slot)
        menu.addAction(action)
        self.addAction(action)
        return action

    def _build_menus(self) -> None:
        menus = self.menuBar()
        file_menu = menus.addMenu("&File")
        self._action(file_menu, "&Open…", self._open_dialog, "Ctrl+O")
        self._action(file_menu, "Open measurement &directory…", self._open_directory_dialog, "Ctrl+Shift+O")
        self.recent_menu = file_menu.addMenu("Open &recent")
        self._fill_recent()
        file_menu.addSeparator()
        self._action(file_menu, "&Write profile", lambda: self._export(), "Ctrl+E")
        file_menu.addSeparator()
        self._action(file_menu, "&Quit", self.close, "Ctrl+Q")
        calibration = menus.addMenu("&Calibration")
        calibrate = self.pages["calibrate"]
        self._action(calibration, "&Start / resume", lambda: calibrate.start(), "Ctrl+R")
        self._action(calibration, "&Pause / resume", calibrate.toggle_pause, "Ctrl+P")
        self._action(calibration, "&Cancel", calibrate.cancel, "Ctrl+.")
        view = menus.addMenu("&View")
        for i, (key, module, name, title) in enumerate(PAGES):
            self._action(view, f"{i + 1} {title}", lambda checked=False, key=key: self.show_page(key),
                         f"Ctrl+{i + 1}")
        view.addSeparator()
        toggle = self.log_dock.toggleViewAction()
        toggle.setShortcut(QKeySequence("Ctrl+L"))
        view.addAction(toggle)
        self.addAction(toggle)
        help_menu = menus.addMenu("&Help")
        self._action(help_menu, "&Keyboard shortcuts", self._show_shortcuts)

    def _fill_recent(self) -> None:
        self.recent_menu.clear()
        recent = self.settings.recent_files()
        for path in recent:
            action = self.recent_menu.addAction(path)
            action.triggered.connect(lambda checked=False, p=path: self.open_path(p))
        self.recent_menu.setEnabled(bool(recent))

    def _show_shortcuts(self) -> None:
        box = QMessageBox(QMessageBox.Icon.Information, "Keyboard shortcuts",
                          "\n".join(f"{keys}\t{what}" for keys, what in SHORTCUTS), parent=self)
        box.open()

    # -- pages ------------------------------------------------------------------------------
    def page(self, key: str):
        """The page ``key``, built now if it was still pending."""
        if key in self._pending:
            index = [k for k, *_ in PAGES].index(key)
            _, module, name, title = PAGES[index]
            placeholder = self._pending.pop(key)
            page = _make_page(module, name, title, self.workspace)
            current = self.stack.currentIndex()
            self.stack.insertWidget(index, page)
            self.stack.removeWidget(placeholder)
            placeholder.deleteLater()
            self.stack.setCurrentIndex(current)
            self.pages[key] = page
            self._wire(key, page)
        return self.pages[key]

    def _wire(self, key: str, page) -> None:
        """Connect what a page asks of the others (pages built later are wired when built)."""
        if key == "diagnose" and hasattr(page, "follow_up_requested"):
            page.follow_up_requested.connect(self.measure_follow_up)
        if hasattr(page, "use_headset_browser"):
            page.use_headset_browser(self.headset_browser)

    def measure_follow_up(self, plan_path, out_dir) -> str:
        """Measure a follow-up plan on the Calibrate page (into ``out_dir``; a new session without one)."""
        self.show_page("calibrate")
        return self.pages["calibrate"].measure_follow_up(plan_path, out_dir)

    def _build_next_page(self) -> None:
        if self._pending and not getattr(self, "_shut_down", False):
            self.page(next(iter(self._pending)))
            QTimer.singleShot(0, self._build_next_page)

    def showEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().showEvent(event)
        if self._pending:
            QTimer.singleShot(0, self._build_next_page)

    def show_page(self, key: str) -> None:
        self.stack.setCurrentWidget(self.page(key))

    def current_page_key(self) -> str:
        return PAGES[self.stack.currentIndex()][0]

    def _export(self) -> None:
        self.show_page("export")
        self.page("export").export()

    # -- files -------------------------------------------------------------------------------
    def _open_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Open a session or a profile", "", OPEN_FILTER)
        if path:
            self.open_path(path)

    def _open_directory_dialog(self) -> None:
        path = QFileDialog.getExistingDirectory(self, "Open a measurement directory")
        if path:
            self.open_path(path)

    def ask_resume(self, journal) -> bool:
        """Ask whether to resume an unfinished calibration (tests replace this)."""
        done = sum(1 for r in journal.latest().values() if r.ok)
        answer = QMessageBox.question(
            self, "Resume the calibration?",
            f"{journal.path.parent} holds an unfinished calibration: {done} of {len(journal.header.plan)} "
            "patches measured. Resume it?")
        return answer == QMessageBox.StandardButton.Yes

    def open_path(self, path) -> None:
        """Open ``path`` as ``diagnose`` would (off the GUI thread); an unfinished calibration is offered to resume."""
        path = Path(path)
        journal = None
        if path.is_dir():
            try:
                journal = unfinished_journal(path)
            except Exception as error:  # noqa: BLE001 - a broken journal is reported, not raised
                self.report_error(str(error))
                return
        if journal is not None:
            if self.ask_resume(journal):
                calibrate = self.pages["calibrate"]
                calibrate.form.out_dir.setText(str(path))
                self.show_page("calibrate")
                try:
                    setup = calibrate.form.setup(
                        instrument="simulated" if journal.header.settings.get("simulated")
                        else calibrate.form.instrument.currentData(), effects={})
                except WorkbenchError as error:  # e.g. a patch server address that is not HOST:PORT
                    self.report_error(f"cannot resume {path}: {error}")
                    return
                calibrate.start(setup)
            return
        self.statusBar().showMessage(f"opening {path}…")
        loader = CallWorker(lambda: load_path(path), self)
        loader.done.connect(self._loaded)
        loader.failed.connect(lambda message: self.report_error(f"could not open {path}: {message}"))
        loader.finished.connect(lambda: self._loaders.remove(loader))
        self._loaders.append(loader)
        loader.start()

    def _loaded(self, loaded) -> None:
        try:
            self.workspace.apply(loaded)
        except Exception as error:  # noqa: BLE001 - a view failing must reach the user, not stderr
            self.report_error(f"could not show {loaded.path}: {describe_error(error)}")
            return
        self.settings.add_recent(loaded.path)
        self._fill_recent()
        self.statusBar().showMessage(f"opened {loaded.path}", 5000)
        self.show_page("diagnose")
        self.file_loaded.emit(loaded)

    def report_error(self, message: str) -> None:
        """Say what failed: status bar, log, and a (non-blocking) message box."""
        _LOG.error("%s", message)
        self.statusBar().showMessage(message)
        self.error.emit(message)
        box = QMessageBox(QMessageBox.Icon.Warning, "Workbench", message, parent=self)
        box.setObjectName("error-box")
        box.open()

    # -- title and status ------------------------------------------------------------------------
    def _update_title(self) -> None:
        ws = self.workspace
        session = ws.session_path.name if ws.session_path else "no session"
        if ws.profile_path:
            profile = ws.profile_path.name
        else:
            profile = ws.profile.device.get("name", "profile")
            if ws.session is not None and ws.profile.device.get("source") == getattr(ws.session, "source", None):
                profile += " (the session's model, not saved yet)"
        self.setWindowTitle(f"VR colour workbench — {session} — profile: {profile}")

    def _update_status(self) -> None:
        state = self.workspace.measurement
        calibrate = self.pages["calibrate"]
        if state.status == "idle":
            try:
                setup = calibrate.form.setup()
                instrument, display = setup.describe_instrument(), setup.describe_display()
            except Exception:  # noqa: BLE001 - an incomplete form names nothing yet
                instrument, display = "—", "—"
            status = ""
        else:
            instrument, display = state.instrument, state.display
            status = f" ({state.status}, {state.done} of {state.total})"
        self.instrument_label.setText(f"instrument: {instrument}{status}")
        self.display_label.setText(f"patch display: {display}")

    # -- teardown -------------------------------------------------------------------------------------
    def shutdown(self) -> None:
        """Stop every worker and wait for it; save the layout (idempotent)."""
        if getattr(self, "_shut_down", False):
            return
        self._shut_down = True
        self.settings.save_layout(self.saveGeometry(), self.saveState())
        self.pages["calibrate"].stop()
        for loader in list(self._loaders):
            loader.wait()
        for page in self.pages.values():
            stop = getattr(page, "shutdown", None)
            if callable(stop):
                stop()
        self.headset_browser.shutdown()
        self.log_dock.detach()

    def closeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        self.shutdown()
        super().closeEvent(event)
