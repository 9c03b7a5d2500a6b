"""The log dock: the workbench's log messages, and the instrument's traffic at DEBUG on demand."""

from __future__ import annotations

import logging

from PySide6.QtCore import QObject, Qt, Signal
from PySide6.QtGui import QFontDatabase
from PySide6.QtWidgets import QCheckBox, QDockWidget, QPlainTextEdit, QVBoxLayout, QWidget

__all__ = ["LogDock", "INSTRUMENT_LOGGER"]

INSTRUMENT_LOGGER = "instruments"
"""Logger of the instrument drivers; at DEBUG it logs every frame sent and received."""

_MAX_LINES = 5000
_LOGGERS = ("workbench", INSTRUMENT_LOGGER)


class _Relay(QObject):
    line = Signal(str)


class _QtLogHandler(logging.Handler):
    """Hands formatted records to the GUI thread through a queued signal (records come from any thread)."""

    def __init__(self, relay: _Relay):
        super().__init__()
        self.relay = relay
        self.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s", "%H:%M:%S"))

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.relay.line.emit(self.format(record))
        except RuntimeError:  # the dock is gone (teardown)
            pass


class LogDock(QDockWidget):
    """A dock with the log; a check box turns the instrument traffic (DEBUG) on and off."""

    def __init__(self, parent=None):
        super().__init__("Log", parent)
        self.setObjectName("log-dock")
        body = QWidget()
        layout = QVBoxLayout(body)
        layout.setContentsMargins(4, 4, 4, 4)
        self.traffic = QCheckBox("Show instrument traffic (DEBUG)")
        self.text = QPlainTextEdit(readOnly=True)
        self.text.setMaximumBlockCount(_MAX_LINES)
        self.text.setFont(QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont))
        layout.addWidget(self.traffic)
        layout.addWidget(self.text)
        self.setWidget(body)
        self._relay = _Relay()
        self._relay.line.connect(self.text.appendPlainText, Qt.ConnectionType.QueuedConnection)
        self.handler = _QtLogHandler(self._relay)
        self.handler.setLevel(logging.INFO)
        self.traffic.toggled.connect(self.set_traffic)
        self._levels = {name: logging.getLogger(name).level for name in _LOGGERS}
        # Handlers already on the root (the CLI's stderr handler) keep showing only what they showed
        # before, although the workbench loggers now pass INFO on to the dock.
        root = logging.getLogger()
        self._quietened = [h for h in root.handlers if h.level == logging.NOTSET]
        for handler in self._quietened:
            handler.setLevel(root.level)
        for name in _LOGGERS:
            logger = logging.getLogger(name)
            logger.addHandler(self.handler)
            if logger.getEffectiveLevel() > logging.INFO:
                logger.setLevel(logging.INFO)

    def set_traffic(self, on: bool) -> None:
        """Log every instrument frame (DEBUG) in the dock, or stop."""
        self.handler.setLevel(logging.DEBUG if on else logging.INFO)
        instrument = logging.getLogger(INSTRUMENT_LOGGER)
        instrument.setLevel(logging.DEBUG if on else logging.INFO)

    def detach(self) -> None:
        """Stop receiving log records (at teardown)."""
        for name, level in self._levels.items():
            logging.getLogger(name).removeHandler(self.handler)
            logging.getLogger(name).setLevel(level)
        for handler in self._quietened:
            handler.setLevel(logging.NOTSET)
