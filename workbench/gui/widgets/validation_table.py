"""The validation colours: a sortable table (swatches of measured vs predicted, ΔE00) and the ΔE00 histogram."""

from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QIcon, QPainter, QPixmap
from PySide6.QtWidgets import (QAbstractItemView, QHeaderView, QStyle, QTableWidget, QTableWidgetItem,
                               QVBoxLayout, QWidget)

from workbench.gui import diagnosis_views as views
from workbench.gui.widgets.plot_view import brush, configure_plot, pen

__all__ = ["ValidationTable", "ValidationHistogram", "swatch_icon"]

_COLUMNS = ("measured\n| ext. | base", "DAC\nr, g, b", "ΔE00\next.", "ΔE00\nbase")
"""Two-line, short headers (their tooltips say them in full), so that the four columns fit the 300
pixels the table has on a 1366 x 768 screen (one-line headers and a swatch column for each model
made it scroll sideways)."""

_TIPS = ("the measured colour, then the extended model's and the baseline's prediction of it "
         "(sRGB, clipped to the display's range)",
         "the colour's drive values", "CIEDE2000 between measured and the extended model",
         "CIEDE2000 between measured and the baseline (gamma + 3x3)")

SWATCH_SIZE = (54, 18)
"""Pixels of a swatch icon: three parts of 18 x 18."""


def swatch_icon(*colours, size: tuple[int, int] = SWATCH_SIZE) -> QIcon:
    """An icon of equal parts side by side, one per 8-bit sRGB colour, left to right."""
    width, height = size
    pixmap = QPixmap(width, height)
    pixmap.fill(QColor(*colours[0]))
    painter = QPainter(pixmap)
    for i, colour in enumerate(colours[1:], start=1):
        left = i * width // len(colours)
        painter.fillRect(left, 0, width - left, height, QColor(*colour))
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
        for column, tip in enumerate(_TIPS):
            self.horizontalHeaderItem(column).setToolTip(tip)
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.verticalHeader().setVisible(False)
        header = self.horizontalHeader()
        # the swatches as wide as their icons, the drives as their text; the ΔE00 columns share the rest
        # (Qt sizes a header to its label on one line, so the two-line labels' widths are our own)
        for column, content in ((0, SWATCH_SIZE[0] + 12), (1, self._text_width("255, 255, 255"))):
            header.setSectionResizeMode(column, QHeaderView.ResizeMode.Fixed)
            header.resizeSection(column, max(content, self._header_width(column)))
        for column in (2, 3):
            header.setSectionResizeMode(column, QHeaderView.ResizeMode.Stretch)
        self.setIconSize(pg.QtCore.QSize(*SWATCH_SIZE))

    def _text_width(self, text: str) -> int:
        """Pixels a cell needs for ``text`` (its margins included)."""
        margin = self.style().pixelMetric(QStyle.PixelMetric.PM_FocusFrameHMargin, None, self) + 1
        return self.fontMetrics().horizontalAdvance(text) + 2 * margin + 4

    def _header_width(self, column: int) -> int:
        """Pixels a header needs for its longest line, the sort arrow and the margins."""
        header = self.horizontalHeader()
        style, metrics = header.style(), header.fontMetrics()
        margin = style.pixelMetric(QStyle.PixelMetric.PM_HeaderMargin, None, header)
        arrow = style.pixelMetric(QStyle.PixelMetric.PM_HeaderMarkSize, None, header)
        longest = max(metrics.horizontalAdvance(line) for line in _COLUMNS[column].split("\n"))
        return longest + 3 * margin + arrow

    def show_diagnosis(self, diagnosis) -> None:
        rows = () if diagnosis is None else views.validation_rows(diagnosis)
        self.setSortingEnabled(False)
        self.setRowCount(len(rows))
        for i, row in enumerate(rows):
            swatch = QTableWidgetItem("")
            swatch.setIcon(swatch_icon(row.measured_srgb8, row.extended_srgb8, row.baseline_srgb8))
            swatch.setToolTip(_TIPS[0])
            self.setItem(i, 0, swatch)
            self.setItem(i, 1, QTableWidgetItem("{}, {}, {}".format(*row.rgb)))
            self.setItem(i, 2, _Number(row.extended_dE00))
            self.setItem(i, 3, _Number(row.baseline_dE00))
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
