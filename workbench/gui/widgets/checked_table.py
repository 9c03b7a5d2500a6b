"""The effects the diagnosis checked and did not find (or could not test), as a table.

One row per effect of ``to_json()["checked"]`` and ``["untested"]``
(:func:`workbench.gui.diagnosis_views.checked_rows`): the effect, its z against
the critical value, its statistic ± standard error, its impact in ΔE00, and
whether it is in the model or why not (wrapped to the column). The row's
tooltip is everything the diagnosis said about the effect.
"""

from __future__ import annotations

import html

from PySide6.QtCore import Qt
from PySide6.QtGui import QFont
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QSizePolicy, QTableWidget, QTableWidgetItem

from workbench.gui import diagnosis_views as views

__all__ = ["CheckedTable", "CHECKED_COLUMNS"]

CHECKED_COLUMNS = ("effect", "z / critical z", "statistic ± SE", "impact ΔE00", "in the model / why not")
"""The table's columns, in order."""


class CheckedTable(QTableWidget):
    """What was checked and not found; :meth:`show_diagnosis` fills it.

    It asks for the height of every row (up to :attr:`MAX_VISIBLE_LINES` lines of text) and
    makes do with :attr:`MIN_VISIBLE_LINES` (then scrolling), so that the page keeps fitting a
    1366 × 768 screen.
    """

    MAX_VISIBLE_LINES = 8
    MIN_VISIBLE_LINES = 3

    def __init__(self, parent=None):
        super().__init__(0, len(CHECKED_COLUMNS), parent)
        self.setHorizontalHeaderLabels(CHECKED_COLUMNS)
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.setWordWrap(True)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.verticalHeader().setVisible(False)
        self.verticalHeader().setDefaultSectionSize(self.fontMetrics().height() + 6)
        header = self.horizontalHeader()
        for column in range(len(CHECKED_COLUMNS) - 1):
            header.setSectionResizeMode(column, QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(len(CHECKED_COLUMNS) - 1, QHeaderView.ResizeMode.Stretch)
        header.setMinimumSectionSize(40)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Maximum)
        self.setToolTip("effects the diagnosis checked and did not find; hover a row for its evidence")
        self.rows: tuple = ()
        self._fit_height()

    def show_diagnosis(self, diagnosis) -> None:
        self.rows = () if diagnosis is None else views.checked_rows(diagnosis)
        self.setRowCount(len(self.rows))
        for i, row in enumerate(self.rows):
            tooltip = f"<b>{row.effect}</b>: {_escape(row.evidence)}"
            for j, text in enumerate((row.effect, row.test, row.statistic, row.impact, row.model)):
                item = QTableWidgetItem(text)
                item.setToolTip(tooltip if j < 4 else f"{_escape(row.model)}<br><br>{tooltip}")
                if j in (1, 2, 3):
                    item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                if j == 1 and row.significant:
                    font = QFont(item.font())
                    font.setBold(True)
                    item.setFont(font)
                self.setItem(i, j, item)
        self._fit_height()

    def sizeHint(self):  # noqa: N802 - Qt's name
        hint = super().sizeHint()
        hint.setHeight(self.maximumHeight())  # every row (up to MAX_VISIBLE_LINES), as _fit_height set it
        return hint

    def minimumSizeHint(self):  # noqa: N802 - Qt's name
        hint = super().minimumSizeHint()
        hint.setHeight(self.minimumHeight())
        return hint

    def row_texts(self, row: int) -> tuple:
        """The texts of ``row``'s cells, in column order."""
        return tuple(self.item(row, j).text() for j in range(self.columnCount()))

    def resizeEvent(self, event):  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._fit_height()  # the reasons wrap to the new width

    def _fit_height(self) -> None:
        """Rows as high as their wrapped text; the table as high as its rows (up to MAX_VISIBLE_LINES)."""
        self.resizeRowsToContents()
        line = self.verticalHeader().defaultSectionSize()
        rows = sum(self.rowHeight(i) for i in range(self.rowCount())) or line
        frame = self.horizontalHeader().sizeHint().height() + 2 * self.frameWidth()
        most = frame + min(rows, self.MAX_VISIBLE_LINES * line)
        least = frame + min(rows, self.MIN_VISIBLE_LINES * line)
        if (least, most) != (self.minimumHeight(), self.maximumHeight()):
            self.setMinimumHeight(least)
            self.setMaximumHeight(most)
            self.updateGeometry()


def _escape(text: str) -> str:
    return html.escape(text)
