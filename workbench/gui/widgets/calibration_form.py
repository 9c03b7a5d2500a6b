"""The Calibrate page's setup form: instrument, patch display, plan, output directory.

It produces a :class:`~workbench.gui.calibration_setup.CalibrationSetup` and
shows, before anything starts, the plan's patch count and its estimated
instrument time.

It fits a narrow column (the window at 1366 × 768): lists shrink to the
column and elide what does not fit (the whole text in the tooltip and in the
open list), the buttons beside a field sit on their own row under it, the
estimate wraps, and only the chosen patch display's settings show (the screen
and "Identify screens" for a full-screen window, the address and "Test
connection" for a VR application, the engine's address (and the settle time
of the Unity convention) for the seed authors' Unity and Unreal projects, the
address the headset's browser's page is served on (WebXR; the page shows its URL, QR code and
connection state),
the eye for the displays that can show a patch to one eye); nothing needs
horizontal scrolling. The instrument's sync (none, internal at a frequency,
external) sits next to the plan; the adaptive plan's budget, target and
validation colours show when it is chosen.

Choosing "headset browser (WebXR)" starts the window's WebXR server (shared
with the Scene page, :class:`~workbench.gui.headset_browser.HeadsetBrowser`)
at once, so that the URL and its QR code (on the page, beside the progress)
are there to open in the headset before the calibration starts.
"""

from __future__ import annotations

import secrets
import tempfile
from pathlib import Path

from PySide6.QtCore import QEvent, Qt, Signal
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPushButton,
    QSizePolicy,
    QSpinBox,
    QStyle,
    QStyleOptionComboBox,
    QStylePainter,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from instruments.headset import HEADSET_EFFECTS
from workbench.errors import WorkbenchError
from workbench.measurement.plans import MEASUREMENT_PLANS
from instruments.cs2000 import INTERNAL_SYNC_RANGE_HZ, SyncMode
from instruments.engine_displays import RGB_TEXT_DEFAULT_SETTLE_S
from workbench.gui.calibration_setup import (
    DISPLAY_KINDS,
    ENGINE_DEFAULT_ADDRESSES,
    PLAN_DESCRIPTIONS,
    PLAN_NAMES,
    SIMULATED,
    SYNC_CHOICES,
    WEBXR_DEFAULT_ADDRESS,
    CalibrationSetup,
    adaptive_estimate,
    cs2000_ports,
    plan_estimate,
    check_tcp_display,
)
from workbench.measurement.adaptive import (
    ADAPTIVE_PLAN,
    DEFAULT_VALIDATION,
    PAPER_SHARE,
    TIME_CAP_SHARE,
    adaptive_core_plan,
)
from workbench.gui.screen_overlay import identify_screens
from workbench.gui.workers import CallWorker
from workbench.measurement.runner import format_duration

__all__ = ["CalibrationForm", "ElidingComboBox"]


class ElidingComboBox(QComboBox):
    """A list that shrinks to its column: the current text is elided ("…") where it does not fit,
    the whole of it is the tooltip, and the open list is as wide as its longest entry."""

    MIN_CHARACTERS = 12

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.setMinimumContentsLength(self.MIN_CHARACTERS)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.model().rowsInserted.connect(self._fit_popup)
        self.model().modelReset.connect(self._fit_popup)

    def event(self, event):
        if event.type() == QEvent.Type.ToolTip:
            self.setToolTip(self.currentText())
        return super().event(event)

    def _fit_popup(self, *_) -> None:
        view = self.view()
        widest = max((self.fontMetrics().horizontalAdvance(self.itemText(i)) for i in range(self.count())), default=0)
        view.setMinimumWidth(widest + 3 * self.style().pixelMetric(QStyle.PixelMetric.PM_ScrollBarExtent))

    def text_fits(self) -> bool:
        """Whether the current text shows whole (not elided)."""
        return self.fontMetrics().horizontalAdvance(self.currentText()) <= self._text_rect().width()

    def _text_rect(self):
        option = QStyleOptionComboBox()
        self.initStyleOption(option)
        return self.style().subControlRect(QStyle.ComplexControl.CC_ComboBox, option,
                                           QStyle.SubControl.SC_ComboBoxEditField, self)

    def paintEvent(self, event):  # noqa: N802 - Qt's name
        painter = QStylePainter(self)
        option = QStyleOptionComboBox()
        self.initStyleOption(option)
        painter.drawComplexControl(QStyle.ComplexControl.CC_ComboBox, option)
        width = self._text_rect().width() - 2
        option.currentText = self.fontMetrics().elidedText(option.currentText, Qt.TextElideMode.ElideRight, width)
        painter.drawControl(QStyle.ControlElement.CE_ComboBoxLabel, option)


_DISPLAY_TIPS = {
    "tcp": "a VR application speaking vr-workbench-patch/1: it says when each patch is on the panel, shows "
           "APL windows and one eye, and reports errors",
    "rgb-text": "the seed authors' Unity convention: R,G,B sent on a new connection per patch, then a fixed "
                "settle time (no acknowledgement, both eyes, full field only)",
    "value-shot": "the seed authors' Unreal convention: Value:r,g,b sent (again every second) until the engine "
                  "answers SHOT (both eyes, full field only)",
    "webxr": "the workbench's WebXR page in the headset's own browser (Quest, Pico; Chrome or Edge with an "
             "OpenXR runtime): open its URL or scan the QR code, press Enter VR; APL windows and one eye",
}


def _field_with_button(field: QWidget, button: QPushButton, beside: QWidget | None = None) -> QWidget:
    """``field`` over ``button`` (the button on its own row, at its full width, left-aligned; ``beside``
    after it on that row)."""
    box = QWidget()
    column = QVBoxLayout(box)
    column.setContentsMargins(0, 0, 0, 0)
    column.setSpacing(4)
    column.addWidget(field)
    row = QHBoxLayout()
    row.addWidget(button)
    if beside is not None:
        row.addWidget(beside, 1)
    else:
        row.addStretch(1)
    column.addLayout(row)
    return box


def _slot() -> QWidget:
    """An empty place in a row for a widget that moves between rows (the eye, with the chosen display)."""
    slot = QWidget()
    layout = QHBoxLayout(slot)
    layout.setContentsMargins(0, 0, 0, 0)
    return slot


def _form(group: QGroupBox) -> QFormLayout:
    """A form whose fields take the column's width; a field too wide to sit beside its label goes below it."""
    form = QFormLayout(group)
    form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
    form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
    return form


class CalibrationForm(QWidget):
    """The setup of a calibration; :meth:`setup` returns it, :attr:`changed` fires on every edit."""

    changed = Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self._instrument_group())
        layout.addWidget(self._display_group())
        layout.addWidget(self._plan_group())
        layout.addStretch(1)
        self._workers: list = []
        self.changed.connect(self._update_estimate)
        self._instrument_changed()
        self._display_changed()
        self._plan_changed()
        self._update_estimate()

    # -- groups -----------------------------------------------------------------------
    def _instrument_group(self) -> QGroupBox:
        group = QGroupBox("Instrument")
        form = _form(group)
        self.instrument = ElidingComboBox()
        self.refresh_ports = QPushButton("Find CS-2000")
        self.refresh_ports.setToolTip("list the serial ports whose USB VID/PID is a CS-2000's (0x132B/0x2104)")
        form.addRow("CS-2000", _field_with_button(self.instrument, self.refresh_ports))
        self.effects: dict = {}
        effects = QWidget()
        grid = QFormLayout(effects)
        grid.setContentsMargins(0, 0, 0, 0)
        for effect_id, spec in HEADSET_EFFECTS.items():
            check = QCheckBox(effect_id)
            check.setToolTip(spec.summary)
            magnitude = QDoubleSpinBox(decimals=3, singleStep=spec.default / 4 or 0.001)
            magnitude.setRange(spec.limits[0], spec.limits[1] - 1e-6)
            magnitude.setValue(spec.default)
            magnitude.setToolTip(spec.magnitude)
            check.toggled.connect(self.changed)
            magnitude.valueChanged.connect(self.changed)
            grid.addRow(check, magnitude)
            self.effects[effect_id] = (check, magnitude)
        self.effects_box = effects
        form.addRow("simulated effects", effects)
        self.time_scale = QDoubleSpinBox(decimals=4, singleStep=0.01)
        self.time_scale.setRange(0.0, 1.0)
        self.time_scale.setValue(0.01)
        self.time_scale.setToolTip("fraction of the real instrument timing the emulator waits (1 = real)")
        form.addRow("time scale", self.time_scale)
        self.refresh_ports.clicked.connect(self.find_ports)
        self.instrument.currentIndexChanged.connect(self._instrument_changed)
        self.find_ports()
        return group

    def _display_group(self) -> QGroupBox:
        group = QGroupBox("Patch display")
        form = _form(group)
        self.display = ElidingComboBox()
        for kind, name in DISPLAY_KINDS.items():
            self.display.addItem(name, kind)
            if kind in _DISPLAY_TIPS:
                self.display.setItemData(self.display.count() - 1, _DISPLAY_TIPS[kind], Qt.ItemDataRole.ToolTipRole)
        form.addRow("show patches on", self.display)
        self.screen = ElidingComboBox()
        for i, screen in enumerate(QGuiApplication.screens()):
            geometry = screen.geometry()
            self.screen.addItem(f"{i}: {screen.name()} {geometry.width()}×{geometry.height()}", i)
        self.screen.setCurrentIndex(self.screen.count() - 1)
        self.identify = QPushButton("Identify screens")
        self.identify.setToolTip("show each screen's number on it for a few seconds")
        self.identify.clicked.connect(lambda: identify_screens(self))
        self._screen_row = _field_with_button(self.screen, self.identify)
        form.addRow("screen", self._screen_row)
        self.eye = ElidingComboBox()
        for eye, name in (("both", "both eyes"), ("left", "left eye"), ("right", "right eye")):
            self.eye.addItem(name, eye)
        self.eye.setToolTip("which panel shows the patches (the other is black); the journal, session and "
                            "profile record it")
        self.tcp = QLineEdit("127.0.0.1:47800")
        self.test_tcp = QPushButton("Test connection")
        self.test_tcp.setToolTip("say hello to the VR application's patch server at this address")
        self.test_tcp.clicked.connect(self.test_connection)
        self._tcp_eye_slot = _slot()
        self._tcp_row = _field_with_button(self.tcp, self.test_tcp, self._tcp_eye_slot)
        form.addRow("patch server", self._tcp_row)
        self.tcp_status = QLabel("")
        self.tcp_status.setWordWrap(True)
        form.addRow("", self.tcp_status)
        self.engine = QLineEdit("{}:{}".format(*ENGINE_DEFAULT_ADDRESSES["rgb-text"]))
        self.engine.setToolTip("where the Unity (port 55001) or Unreal (port 8890) project listens, HOST:PORT")
        self.settle = QDoubleSpinBox(decimals=2, singleStep=0.5, suffix=" s settle")
        self.settle.setRange(0.0, 60.0)
        self.settle.setValue(RGB_TEXT_DEFAULT_SETTLE_S)
        self.settle.setToolTip("the Unity convention sends no acknowledgement: seconds to wait after each patch "
                               "before measuring (the authors wait 2 s)")
        self._engine_row = QWidget()
        row = QHBoxLayout(self._engine_row)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.engine, 1)
        row.addWidget(self.settle)
        form.addRow("engine", self._engine_row)
        self.webxr_address = QLineEdit("{}:{}".format(*WEBXR_DEFAULT_ADDRESS))
        self.webxr_address.setToolTip("where the page is served, HOST:PORT: 127.0.0.1 for a PC headset's browser "
                                      "(or a Quest on USB with adb reverse); 0.0.0.0 for a standalone headset "
                                      "on the network (the URL then has a token, and HTTPS)")
        self.webxr_server_button = QPushButton("Start server")
        self.webxr_server_button.setToolTip("serve the WebXR page (the Scene page shares the server)")
        self.webxr_server_button.clicked.connect(self._toggle_webxr_server)
        self._webxr_eye_slot = _slot()
        self._webxr_row = _field_with_button(self.webxr_address, self.webxr_server_button, self._webxr_eye_slot)
        form.addRow("serve page on", self._webxr_row)
        self.webxr_status = QLabel("")
        self.webxr_status.setWordWrap(True)
        form.addRow("", self.webxr_status)
        self._headset_service = None
        self._display_form = form
        self._engine_kind = "rgb-text"
        self.display.currentIndexChanged.connect(self._display_changed)
        return group

    def _plan_group(self) -> QGroupBox:
        group = QGroupBox("Plan and output")
        form = _form(group)
        self.plan = ElidingComboBox()
        for name in PLAN_NAMES:
            if name == ADAPTIVE_PLAN:
                self.plan.addItem(f"{name} (a core of {len(adaptive_core_plan(0))}, then grows)", name)
            else:
                self.plan.addItem(f"{name} ({len(MEASUREMENT_PLANS[name](0))} patches)", name)
            if name in PLAN_DESCRIPTIONS:
                self.plan.setItemData(self.plan.count() - 1, PLAN_DESCRIPTIONS[name], Qt.ItemDataRole.ToolTipRole)
        self.plan.addItem("from a file…", "file")
        form.addRow("plan", self.plan)
        self.sync = ElidingComboBox()
        for mode, name in SYNC_CHOICES.items():
            self.sync.addItem(name, mode)
        self.sync.setToolTip("the CS-2000's synchronisation to the panel: a low-persistence HMD panel flashes "
                             "once a frame, and unsynchronised measurements of it scatter")
        self.sync_hz = QDoubleSpinBox(decimals=2, singleStep=1.0, suffix=" Hz")
        self.sync_hz.setRange(*INTERNAL_SYNC_RANGE_HZ)
        self.sync_hz.setValue(90.0)
        self.sync_hz.setToolTip("the panel's refresh rate (HTC Vive 90 Hz)")
        sync_row = QWidget()
        row = QHBoxLayout(sync_row)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.sync, 1)
        row.addWidget(self.sync_hz)
        form.addRow("sync", sync_row)
        self.sync.currentIndexChanged.connect(
            lambda: self.sync_hz.setEnabled(self.sync.currentData() == "internal"))
        self.sync_hz.setEnabled(False)
        row = QHBoxLayout()
        self.plan_file = QLineEdit()
        self.plan_file.setPlaceholderText("CSV with columns kind,r,g,b")
        browse = QToolButton(text="…", toolTip="choose a plan file")
        browse.clicked.connect(self._choose_plan_file)
        row.addWidget(self.plan_file, 1)
        row.addWidget(browse)
        self._plan_file_row = QWidget()
        self._plan_file_row.setLayout(row)
        row.setContentsMargins(0, 0, 0, 0)
        form.addRow("plan file", self._plan_file_row)
        self.budget = QDoubleSpinBox(decimals=1, singleStep=1.0, suffix=" min budget")
        self.budget.setRange(0.0, 600.0)
        self.budget.setSpecialValueText("auto budget")
        self.budget.setToolTip(f"instrument time the session may take (measure --budget-min); auto: "
                               f"{PAPER_SHARE:.0%} of what the paper plan would take on this display, never "
                               "less than the core and the validation colours")
        self.target = QDoubleSpinBox(decimals=2, singleStep=0.05, prefix="stop at ΔE00 ")
        self.target.setRange(0.0, 10.0)
        self.target.setSpecialValueText("no target")
        self.target.setToolTip("stop once the predicted held-out mean ΔE00 is at or below this "
                               "(measure --target-dE00); no target: the budget and the floor of improvement "
                               "per minute decide")
        self.validation = QSpinBox(suffix=" validation")
        self.validation.setRange(2, 200)
        self.validation.setValue(DEFAULT_VALIDATION)
        self.validation.setToolTip("seeded random colours measured at the end and never used to fit or to "
                                   "choose: the honest score, with its 95 % confidence interval (measure "
                                   "--validation)")
        self._adaptive_row = QWidget()
        row = QHBoxLayout(self._adaptive_row)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.budget, 1)
        row.addWidget(self.target, 1)
        form.addRow("adaptive", self._adaptive_row)
        self._plan_form = form
        self.plan.currentIndexChanged.connect(self._plan_changed)
        self.seed = QSpinBox()
        self.seed.setRange(0, 2**31 - 1)
        self.seed.setValue(secrets.randbelow(2**31))
        self.seed.setToolTip("seeds the validation colours (and the simulated instrument's noise)")
        seed_row = QWidget()
        row = QHBoxLayout(seed_row)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(self.seed, 1)
        row.addWidget(self.validation, 1)  # the adaptive plan's: shown with it (one row less than its own)
        form.addRow("seed", seed_row)
        self.estimate = QLabel("")
        self.estimate.setWordWrap(True)
        self.estimate.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        form.addRow("estimate", self.estimate)
        row = QHBoxLayout()
        self.out_dir = QLineEdit(str(Path(tempfile.gettempdir()) / "vr-workbench-calibration"))
        out_browse = QToolButton(text="…", toolTip="choose the output directory")
        self.out_dir.setToolTip(self.out_dir.text())  # a long path shows whole here
        self.out_dir.textChanged.connect(self.out_dir.setToolTip)
        out_browse.clicked.connect(self._choose_out_dir)
        row.addWidget(self.out_dir, 1)
        row.addWidget(out_browse)
        form.addRow("output directory", row)
        for signal in (self.plan.currentIndexChanged, self.plan_file.textChanged, self.seed.valueChanged,
                       self.out_dir.textChanged, self.time_scale.valueChanged, self.instrument.currentIndexChanged,
                       self.display.currentIndexChanged, self.sync.currentIndexChanged, self.sync_hz.valueChanged,
                       self.eye.currentIndexChanged, self.engine.textChanged, self.settle.valueChanged,
                       self.webxr_address.textChanged, self.budget.valueChanged, self.target.valueChanged,
                       self.validation.valueChanged):
            signal.connect(self.changed)
        return group

    # -- behaviour --------------------------------------------------------------------
    def find_ports(self) -> None:
        """Refill the instrument list: the simulation, each CS-2000 found by VID/PID, and auto."""
        current = self.instrument.currentData()
        self.instrument.blockSignals(True)
        self.instrument.clear()
        self.instrument.addItem("simulated CS-2000 (emulator on a pty)", SIMULATED)
        for device, description in cs2000_ports():
            self.instrument.addItem(f"CS-2000 on {device} ({description})", device)
        self.instrument.addItem("auto (the one CS-2000 connected by USB)", "auto")
        index = self.instrument.findData(current)
        self.instrument.setCurrentIndex(max(index, 0))
        self.instrument.blockSignals(False)
        self._instrument_changed()

    def _instrument_changed(self) -> None:
        simulated = self.instrument.currentData() == SIMULATED
        self.effects_box.setEnabled(simulated)
        self.time_scale.setEnabled(simulated)
        simulated_display = self.display.model().item(0) if hasattr(self, "display") else None
        if simulated_display is not None:
            simulated_display.setEnabled(simulated)
            if not simulated and self.display.currentData() == "simulated":
                self.display.setCurrentIndex(1)

    def _display_changed(self) -> None:
        kind = self.display.currentData()
        self.screen.setEnabled(kind == "window")
        self.identify.setEnabled(kind == "window")
        self.tcp.setEnabled(kind == "tcp")
        self.test_tcp.setEnabled(kind == "tcp")
        # Only the chosen display's settings: the form then fits a 1366 × 768 screen without scrolling.
        self._display_form.setRowVisible(self._screen_row, kind == "window")
        self._display_form.setRowVisible(self._tcp_row, kind == "tcp")
        engine = kind in ENGINE_DEFAULT_ADDRESSES
        if engine and kind != self._engine_kind:  # the other convention's default port: take this one's
            if self.engine.text().strip() == "{}:{}".format(*ENGINE_DEFAULT_ADDRESSES[self._engine_kind]):
                self.engine.setText("{}:{}".format(*ENGINE_DEFAULT_ADDRESSES[kind]))
            self._engine_kind = kind
        self.engine.setEnabled(engine)
        self.settle.setVisible(kind == "rgb-text")
        self._display_form.setRowVisible(self._engine_row, engine)
        webxr = kind == "webxr"
        self._display_form.setRowVisible(self._webxr_row, webxr)
        self._display_form.setRowVisible(self.webxr_status, webxr and bool(self.webxr_status.text()))
        slot = self._webxr_eye_slot if webxr else self._tcp_eye_slot
        if self.eye.parent() is not slot:
            slot.layout().addWidget(self.eye)
            self.eye.setVisible(True)  # reparenting hides a widget until the next event-loop turn
        self.eye.setEnabled(kind in ("tcp", "webxr"))
        self._display_form.setRowVisible(self.tcp_status, kind == "tcp" and bool(self.tcp_status.text()))
        if webxr and self._headset_service is not None and not self._headset_service.running:
            self.start_webxr_server()

    def _plan_changed(self) -> None:
        """The plan file's row shows only for a plan from a file, the adaptive plan's settings only for it
        (the form then fits 1366 × 768)."""
        self._plan_form.setRowVisible(self._plan_file_row, self.plan.currentData() == "file")
        adaptive = self.plan.currentData() == ADAPTIVE_PLAN
        self._plan_form.setRowVisible(self._adaptive_row, adaptive)
        self.validation.setVisible(adaptive)

    # -- the headset's browser --------------------------------------------------------------
    def bind_headset_browser(self, service) -> None:
        """Show and drive ``service`` (the window's :class:`~workbench.gui.headset_browser.HeadsetBrowser`)."""
        if self._headset_service is not None:
            self._headset_service.status_changed.disconnect(self._webxr_server_changed)
        self._headset_service = service
        service.status_changed.connect(self._webxr_server_changed)
        self._webxr_server_changed(service.status())
        if self.display.currentData() == "webxr" and not service.running:
            self.start_webxr_server()

    @property
    def headset_browser(self):
        """The :class:`~workbench.gui.headset_browser.HeadsetBrowser` the form drives, or ``None``."""
        return self._headset_service

    def webxr_address_tuple(self) -> tuple:
        """``(host, port)`` of the address field (port 0: a free one)."""
        host, _, port = self.webxr_address.text().strip().rpartition(":")
        if not host or not port.isdigit() or not 0 <= int(port) < 65536:
            raise WorkbenchError(f"page address {self.webxr_address.text()!r} is not HOST:PORT "
                                 "(e.g. 127.0.0.1:47900)")
        return host.strip("[]"), int(port)

    def start_webxr_server(self) -> bool:
        """Serve the page on the address field's HOST:PORT; the panel says what went wrong, if anything."""
        if self._headset_service is None:
            return False
        try:
            host, port = self.webxr_address_tuple()
            self._headset_service.start(host, port)
        except WorkbenchError as error:
            self._set_webxr_status(f"✗ {error}")
            return False
        return True

    def _set_webxr_status(self, text: str) -> None:
        self.webxr_status.setText(text)
        self._display_changed()  # its row shows once it has something to say

    def _toggle_webxr_server(self) -> None:
        service = self._headset_service
        if service is None:
            return
        if service.running:
            if service.in_use:
                self._set_webxr_status(f"✗ {service.IN_USE_MESSAGE}")
                return
            service.stop()
        else:
            self.start_webxr_server()

    def _webxr_server_changed(self, status) -> None:
        running = status is not None
        if running and self.webxr_status.text():
            self._set_webxr_status("")
        self.webxr_server_button.setText("Stop server" if running else "Start server")
        self.webxr_address.setEnabled(not running)
        if running:
            server = self._headset_service.server
            shown = f"{server.host}:{server.port}" if server is not None else None
            if shown and self.webxr_address.text().strip() != shown:
                self.webxr_address.blockSignals(True)
                self.webxr_address.setText(shown)
                self.webxr_address.blockSignals(False)
                self.changed.emit()

    def _set_tcp_status(self, text: str) -> None:
        self.tcp_status.setText(text)
        self._display_changed()  # its row shows once it has something to say

    def _choose_plan_file(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Plan file", "", "CSV plan (*.csv)")
        if path:
            self.plan_file.setText(path)
            self.plan.setCurrentIndex(self.plan.findData("file"))

    def _choose_out_dir(self) -> None:
        path = QFileDialog.getExistingDirectory(self, "Output directory", self.out_dir.text())
        if path:
            self.out_dir.setText(path)

    def tcp_address(self) -> tuple:
        host, _, port = self.tcp.text().strip().rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise WorkbenchError(f"patch server {self.tcp.text()!r} is not HOST:PORT (e.g. 127.0.0.1:47800)")
        return host, int(port)

    def engine_address(self) -> tuple:
        host, _, port = self.engine.text().strip().rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise WorkbenchError(f"engine {self.engine.text()!r} is not HOST:PORT (e.g. 127.0.0.1:55001)")
        return host, int(port)

    def sync_text(self) -> str:
        """The sync chosen, as ``measure --sync`` spells it (``none``, ``internal:90``, ``external``)."""
        mode = self.sync.currentData()
        return SyncMode.parse(f"internal:{self.sync_hz.value():.2f}").text if mode == "internal" else mode

    def test_connection(self) -> None:
        """Say hello to the patch server off the GUI thread; the label says what answered."""
        try:
            host, port = self.tcp_address()
        except WorkbenchError as error:
            self._set_tcp_status(f"✗ {error}")
            return
        self._set_tcp_status(f"connecting to {host}:{port}…")
        worker = CallWorker(lambda: check_tcp_display(host, port))
        worker.done.connect(lambda name: self._set_tcp_status(f"✓ connected: {name}"))
        worker.failed.connect(lambda message: self._set_tcp_status(f"✗ {message}"))
        worker.finished.connect(lambda: self._workers.remove(worker))
        self._workers.append(worker)
        worker.start()

    def stop_workers(self) -> None:
        """Wait for the connection test, if one runs (teardown)."""
        for worker in list(self._workers):
            worker.wait()

    def setup(self, **changes) -> CalibrationSetup:
        """The calibration the form describes (``changes`` override fields, e.g. ``remeasure``).

        Raises
        ------
        WorkbenchError
            If the form is incomplete or inconsistent; the message says what to fix.
        """
        simulated = self.instrument.currentData() == SIMULATED
        kind = self.display.currentData()
        fields = dict(
            out_dir=Path(self.out_dir.text().strip() or "."),
            instrument=self.instrument.currentData(),
            effects={k: m.value() for k, (c, m) in self.effects.items() if c.isChecked()} if simulated else {},
            time_scale=self.time_scale.value() if simulated else 0.0,
            display=kind,
            screen=self.screen.currentData() if kind == "window" else None,
            tcp_address=self.tcp_address() if kind == "tcp" else None,
            webxr_address=self.webxr_address_tuple() if kind == "webxr" else None,
            plan_name=self.plan.currentData(),
            plan_file=Path(self.plan_file.text()) if self.plan.currentData() == "file" else None,
            seed=self.seed.value(),
            engine_address=self.engine_address() if kind in ENGINE_DEFAULT_ADDRESSES else None,
            settle_s=self.settle.value(),
            eye=self.eye.currentData() if kind in ("tcp", "webxr") else "both",
            sync=self.sync_text(),
            budget_min=self.budget.value() or None,
            target_dE00=self.target.value() or None,
            validation=self.validation.value(),
        )
        fields.update(changes)
        return CalibrationSetup(**fields)

    def _update_estimate(self) -> None:
        try:
            setup = self.setup()
            if setup.adaptive:
                self.estimate.setText(self._adaptive_estimate_text(setup))
                return
            self.estimate.setToolTip("")
            estimate = plan_estimate(setup.plan(), setup.effects)
        except WorkbenchError as error:
            self.estimate.setText(f"<span style='color:#b03a2e'>{error}</span>")
            return
        kinds = ", ".join(f"{n} {k}" for k, n in estimate.counts.items())
        what = PLAN_DESCRIPTIONS.get(self.plan.currentData())
        self.estimate.setText((f"{what[0].upper()}{what[1:]}: " if what else "") +
                              f"<b>{estimate.patches} patches</b> ({kinds}); instrument time about "
                              f"<b>{format_duration(estimate.instrument_s)}</b> (dark patches take longest)")

    def _adaptive_estimate_text(self, setup: CalibrationSetup) -> str:
        """Three lines at the narrowest column (the form then fits 1366 × 768); the tooltip says the rest."""
        estimate = adaptive_estimate(setup)
        core = format_duration(estimate.core.instrument_s)
        target = f" or ΔE00 {setup.target_dE00:g}" if setup.target_dE00 else ""
        budget = (f"your <b>{format_duration(estimate.budget_s)}</b> of instrument time{target}"
                  if estimate.budget_given else
                  f"about <b>{format_duration(estimate.budget_s)}</b> of instrument time{target} "
                  f"({PAPER_SHARE * 100:.0f} % of paper's)")
        self.estimate.setToolTip(
            f"The adaptive plan measures a core of {estimate.core.patches} patches (about {core} on the simulated "
            f"headset), then after each patch measures the one that lowers the predicted held-out ΔE00 most per "
            f"second, until the budget ({format_duration(estimate.budget_s)}"
            + ("" if estimate.budget_given else f": {PAPER_SHARE * 100:.0f} % of the paper plan's "
               f"{format_duration(estimate.paper_s)}, never less than the core and the validation colours")
            + ")" + (f", the target ΔE00 {setup.target_dE00:g}" if setup.target_dE00 else "")
            + f" or the floor of improvement per minute; it ends with {estimate.validation} validation colours and "
            f"a white (about {format_duration(estimate.validation_s)}), kept in reserve in the budget"
            + ("." if estimate.validation >= setup.validation else
               f"; {estimate.validation} of the {setup.validation} asked for, as all of them would take the "
               f"session past {TIME_CAP_SHARE * 100:.0f} % of the paper plan's time."))
        return (f"Core of <b>{estimate.core.patches} patches</b> ({core}), grows to {budget}, "
                f"{estimate.validation} validation colours included")
