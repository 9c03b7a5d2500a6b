"""The validation colours: a sortable table (swatches of measured vs predicted, ΔE00) and the ΔE00 histogram."""

from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QIcon, QPixmap
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget

from workbench.gui import diagnosis_views as views
from workbench.gui.widgets.plot_view import brush, configure_plot, pen

__all__ = ["ValidationTable", "ValidationHistogram", "swatch_icon"]

_COLUMNS = ("measured | extended", "DAC r, g, b", "ΔE00 extended", "ΔE00 baseline", "measured | baseline")


def swatch_icon(left, right, size: int = 36) -> QIcon:
    """An icon of two halves: ``left`` and ``right`` 8-bit sRGB."""
    pixmap = QPixmap(size, size // 2)
    pixmap.fill(QColor(*left))
    from PySide6.QtGui import QPainter

    painter = QPainter(pixmap)
    painter.fillRect(size // 2, 0, size - size // 2, size // 2, QColor(*right))
    painter.end()
    return QIcon(pixmap)


class _Number(QTableWidgetItem):
    """A cell that sorts by its number."""

    def __init__(self, value: float):
        super().__init__(f"{value:.2f}")
        self.setData(Qt.ItemDataRole.UserRole, float(value))

    def __lt__(self, other) -> bool:
        return self.data(Qt.ItemDataRole.UserRole) < other.data(Qt.ItemDataRole.UserRole)


class ValidationTable(QTableWidget):
    """One row per held-out colour, worst first; click a header to sort."""

    def __init__(self, parent=None):
        super().__init__(0, len(_COLUMNS), parent)
        self.setHorizontalHeaderLabels(_COLUMNS)
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.verticalHeader().setVisible(False)
        self.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.setIconSize(pg.QtCore.QSize(36, 18))

    def show_diagnosis(self, diagnosis) -> None:
        rows = () if diagnosis is None else views.validation_rows(diagnosis)
        self.setSortingEnabled(False)
        self.setRowCount(len(rows))
        for i, row in enumerate(rows):
            first = QTableWidgetItem("")
            first.setIcon(swatch_icon(row.measured_srgb8, row.extended_srgb8))
            last = QTableWidgetItem("")
            last.setIcon(swatch_icon(row.measured_srgb8, row.baseline_srgb8))
            self.setItem(i, 0, first)
            self.setItem(i, 1, QTableWidgetItem("{}, {}, {}".format(*row.rgb)))
            self.setItem(i, 2, _Number(row.extended_dE00))
            self.setItem(i, 3, _Number(row.baseline_dE00))
            self.setItem(i, 4, last)
        self.setSortingEnabled(True)
        self.sortItems(2, Qt.SortOrder.DescendingOrder)

    def values(self, column: int) -> list:
        """The numbers of a ΔE00 column, top to bottom (as sorted)."""
        return [self.item(r, column).data(Qt.ItemDataRole.UserRole) for r in range(self.rowCount())]


class ValidationHistogram(pg.PlotWidget):
    """ΔE00 histograms of baseline and extended side by side (two bar series on the same bins)."""

    def __init__(self, parent=None):
        super().__init__(parent, background="w")
        self.setMinimumSize(240, 180)
        plot = self.getPlotItem()
        configure_plot(plot, "ΔE00 on held-out colours", "ΔE00", "colours")
        self.legend = plot.addLegend(offset=(-5, 5), labelTextSize="8pt")
        self.bars = {name: pg.BarGraphItem(x=[], height=[], width=0.1, brush=brush(c, 170), pen=pen(c, 1))
                     for name, c in (("baseline", 3), ("extended", 2))}
        for name, item in self.bars.items():
            plot.addItem(item)
            self.legend.addItem(item, name)

    def show_diagnosis(self, diagnosis) -> None:
        view = None if diagnosis is None else views.histogram_view(diagnosis)
        if view is None:
            for item in self.bars.values():
                item.setOpts(x=[], height=[])
            return
        width = float(view.series[0].x[1] - view.series[0].x[0]) if len(view.series[0].x) > 1 else 1.0
        for offset, series in zip((-0.22, 0.22), view.series):
            self.bars[series.name].setOpts(x=series.x + offset * width, height=series.y, width=0.42 * width)
        self.getPlotItem().enableAutoRange()
