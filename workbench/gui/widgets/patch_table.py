"""The plan's patches as a table: status, luminance, and the reason of a failure; pick some to re-measure."""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QBrush, QColor
from PySide6.QtWidgets import (
    QAbstractItemView,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

__all__ = ["PatchTable"]

_COLUMNS = ("#", "kind", "DAC r, g, b", "status", "Lv, cd/m²", "note")
_FAILED = QBrush(QColor("#f5c6c0"))
_SUPERSEDED = QBrush(QColor("#fdf2c4"))
_NONE = QBrush()
_WIDEST_STATUS = "measuring…"
_CELL_PADDING_PX = 10  # a cell's margins either side of its text (resizeColumnsToContents adds 7)


class PatchTable(QWidget):
    """One row per patch of the plan.

    Attributes
    ----------
    remeasure(list)
        The plan indices the user asked to measure again (selected rows, or
        the failed ones).
    """

    remeasure = Signal(list)

    def __init__(self, parent=None):
        super().__init__(parent)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.table = QTableWidget(0, len(_COLUMNS))
        self.table.setHorizontalHeaderLabels(_COLUMNS)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.verticalHeader().setVisible(False)
        # Columns are sized to their contents when a plan is set and widened when a cell needs it,
        # not by the header on every change: that scanned every row at each update (7.6 ms a
        # patch on 250 rows, 31 ms on 1000, in the window's own thread).
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        header.setStretchLastSection(True)
        layout.addWidget(self.table)
        buttons = QHBoxLayout()
        self.failures = QLabel("")
        self.failures.setWordWrap(True)
        self.remeasure_selected = QPushButton("Re-measure selected")
        self.remeasure_selected.setToolTip("measure the selected patches again; the journal keeps both "
                                           "records and the newer one wins")
        self.remeasure_failed = QPushButton("Re-measure failed")
        buttons.addWidget(self.failures, 1)
        buttons.addWidget(self.remeasure_failed)
        buttons.addWidget(self.remeasure_selected)
        layout.addLayout(buttons)
        self.remeasure_selected.clicked.connect(lambda: self.remeasure.emit(self.selected_indices()))
        self.remeasure_failed.clicked.connect(lambda: self.remeasure.emit(self.failed_indices()))
        self._status: dict = {}
        self._reasons: dict = {}
        self.set_idle(True)

    def set_plan(self, plan, journal=None) -> None:
        """One row per patch; a journal (resume) fills in what was already measured."""
        self.table.setSortingEnabled(False)
        self.table.setRowCount(len(plan))
        self._status, self._reasons = {}, {}
        for index, patch in enumerate(plan.patches):
            self._put_row(index, patch)
        if journal is not None:
            for record in journal.records:
                self.set_record(record)
        self.table.resizeColumnsToContents()
        self._widen(3, _WIDEST_STATUS)
        self._update_failures()

    def add_patch(self, index: int, patch) -> None:
        """A row for a patch a dynamic plan (the adaptive one) has added, if it has none yet."""
        if index < self.table.rowCount():
            return
        self.table.setRowCount(index + 1)
        for column, text in enumerate(self._put_row(index, patch)):
            self._widen(column, text)

    def _put_row(self, index: int, patch) -> tuple:
        """Fill row ``index`` with ``patch``, pending; returns the row's texts."""
        texts = (str(index), patch.kind, "{}, {}, {}".format(*patch.rgb), "pending", "", "")
        for column, text in enumerate(texts):
            item = QTableWidgetItem(text)
            if column == 0:
                item.setData(Qt.ItemDataRole.UserRole, index)
            self.table.setItem(index, column, item)
        return texts

    def set_measuring(self, index: int) -> None:
        self._set(index, 3, "measuring…")
        self.table.scrollToItem(self.table.item(index, 0))

    def set_record(self, record) -> None:
        """Show a journal record; a later record of the same patch supersedes the earlier one, and says so."""
        index = record.index
        previous = self._status.get(index)
        note = record.reason if not record.ok else (record.warning or "")
        if previous is not None:
            note = f"re-measured; supersedes the earlier {previous} record" + (f" — {note}" if note else "")
        self._status[index] = record.status
        self._reasons[index] = record.reason
        self._set(index, 3, "ok" if record.ok else "FAILED")
        self._set(index, 4, f"{record.Lv:.4g}" if record.ok and record.Lv is not None else "")
        self._set(index, 5, note)
        self.table.item(index, 5).setToolTip(note)  # the note column ends at the table's edge
        colour = _FAILED if not record.ok else (_SUPERSEDED if previous is not None else _NONE)
        for column in range(len(_COLUMNS)):
            self.table.item(index, column).setBackground(colour)
        self._update_failures()

    def _set(self, row: int, column: int, text: str) -> None:
        item = self.table.item(row, column)
        if item is not None:
            item.setText(text)
            self._widen(column, text)

    def _widen(self, column: int, text: str) -> None:
        """Widen ``column`` to show ``text`` whole (the last column stretches to the table's edge)."""
        if column == len(_COLUMNS) - 1:
            return
        width = self.table.fontMetrics().horizontalAdvance(text) + _CELL_PADDING_PX
        if width > self.table.columnWidth(column):
            self.table.setColumnWidth(column, width)

    def _update_failures(self) -> None:
        failed = self.failed_indices()
        self.failures.setText("" if not failed else
                              f"<span style='color:#b03a2e'><b>{len(failed)} failed</b>: " + "; ".join(
                                  f"#{i}: {self._reasons[i]}" for i in failed[:3]) + ("; …" if len(failed) > 3 else "")
                              + "</span>")
        self.remeasure_failed.setEnabled(self._idle and bool(failed))

    def failed_indices(self) -> list:
        return sorted(i for i, status in self._status.items() if status != "ok")

    def selected_indices(self) -> list:
        rows = {item.row() for item in self.table.selectedItems()}
        return sorted(int(self.table.item(r, 0).data(Qt.ItemDataRole.UserRole)) for r in rows)

    def select(self, indices) -> None:
        """Select the rows of these plan indices (what a user's clicks do)."""
        self.table.clearSelection()
        mode = self.table.selectionMode()
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.MultiSelection)
        for index in indices:
            self.table.selectRow(index)
        self.table.setSelectionMode(mode)

    def set_idle(self, idle: bool) -> None:
        """Re-measuring is offered only while no run is going."""
        self._idle = idle
        self.remeasure_selected.setEnabled(idle and self.table.rowCount() > 0)
        self.remeasure_failed.setEnabled(idle and bool(self.failed_indices()))

    def status(self, index: int) -> str:
        return self.table.item(index, 3).text()

    def note(self, index: int) -> str:
        return self.table.item(index, 5).text()
