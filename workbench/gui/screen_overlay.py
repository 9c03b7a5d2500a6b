""""Identify screens": each screen shows its number for a few seconds, so the patch lands on the right one."""

from __future__ import annotations

from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QColor, QFont, QGuiApplication, QPainter
from PySide6.QtWidgets import QWidget

__all__ = ["ScreenNumber", "identify_screens", "SHOW_MS"]

SHOW_MS = 3000
"""How long the numbers stay up."""


class ScreenNumber(QWidget):
    """A frameless window in the middle of one screen showing its index and name."""

    def __init__(self, index: int, screen, parent=None):
        super().__init__(parent, Qt.WindowType.Tool | Qt.WindowType.FramelessWindowHint
                         | Qt.WindowType.WindowStaysOnTopHint)
        self.index = index
        self.text = f"{index}\n{screen.name()}\n{screen.geometry().width()}×{screen.geometry().height()}"
        geometry = screen.geometry()
        size = min(geometry.width(), geometry.height()) // 3
        self.setGeometry(geometry.center().x() - size // 2, geometry.center().y() - size // 2, size, size)

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        painter = QPainter(self)
        painter.fillRect(self.rect(), QColor(20, 20, 20, 230))
        painter.setPen(QColor("white"))
        font = QFont()
        font.setPixelSize(max(12, self.height() // 7))
        painter.setFont(font)
        painter.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter, self.text)
        painter.end()


def identify_screens(parent=None, show_ms: int = SHOW_MS) -> list:
    """Show every screen's number on it for ``show_ms``; returns the windows (they close themselves)."""
    windows = []
    for index, screen in enumerate(QGuiApplication.screens()):
        window = ScreenNumber(index, screen, parent)
        window.show()
        QTimer.singleShot(show_ms, window.close)
        windows.append(window)
    return windows
