"""The patch being measured: nominal DAC colour beside the colour the measurement predicts."""

from __future__ import annotations

from PySide6.QtCore import QRect, Qt
from PySide6.QtGui import QColor, QPainter
from PySide6.QtWidgets import QSizePolicy, QWidget

__all__ = ["SplitSwatch"]


class SplitSwatch(QWidget):
    """Two halves: the nominal DAC values shown as sRGB (left) and a colour the measurement gives (right).

    The right half is what the current profile predicts for the patch while it
    is measured, then the measured colour once the measurement arrives; the
    captions say which.
    """

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setMinimumSize(220, 120)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Preferred)
        self.left = QColor(40, 40, 40)
        self.right = QColor(40, 40, 40)
        self.left_caption = "nominal DAC"
        self.right_caption = ""

    def set_colours(self, left_rgb8, right_rgb8, right_caption: str) -> None:
        self.left = QColor(*(int(v) for v in left_rgb8))
        self.right = QColor(*(int(v) for v in right_rgb8)) if right_rgb8 is not None else QColor(40, 40, 40)
        self.right_caption = right_caption
        self.update()

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        painter = QPainter(self)
        half = self.width() // 2
        for rect, colour, caption in ((QRect(0, 0, half, self.height()), self.left, self.left_caption),
                                      (QRect(half, 0, self.width() - half, self.height()), self.right,
                                       self.right_caption)):
            painter.fillRect(rect, colour)
            text = QColor("black") if colour.lightnessF() > 0.55 else QColor("white")
            painter.setPen(text)
            painter.drawText(rect.adjusted(6, 4, -6, -4), Qt.AlignmentFlag.AlignBottom | Qt.AlignmentFlag.AlignLeft,
                             caption)
        painter.setPen(QColor("#777"))
        painter.drawLine(half, 0, half, self.height())
        painter.drawRect(self.rect().adjusted(0, 0, -1, -1))
        painter.end()
