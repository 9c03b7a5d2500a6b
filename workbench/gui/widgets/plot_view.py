"""A pyqtgraph plot that shows a :class:`~workbench.gui.diagnosis_views.PlotView`, updated in place.

Curves are created once, on the first view that needs them, and later views
only ``setData`` them; pens and brushes are made once per colour.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor

__all__ = ["PALETTE", "pen", "brush", "ViewPlot", "configure_plot", "emptiest_corner", "place_legend"]

PALETTE = ("#c0392b", "#27ae60", "#2e6fd0", "#555555", "#e67e22", "#8e44ad")
"""Colours by index: red, green, blue channels, grey, then two more."""

_PENS: dict = {}
_BRUSHES: dict = {}


def pen(index: int, width: float = 1.6, dashed: bool = False):
    """A cached pen of palette colour ``index``."""
    key = (index, width, dashed)
    if key not in _PENS:
        _PENS[key] = pg.mkPen(PALETTE[index % len(PALETTE)], width=width,
                              style=Qt.PenStyle.DashLine if dashed else Qt.PenStyle.SolidLine)
    return _PENS[key]


def brush(index: int, alpha: int = 255):
    """A cached brush of palette colour ``index``."""
    key = (index, alpha)
    if key not in _BRUSHES:
        colour = QColor(PALETTE[index % len(PALETTE)])
        colour.setAlpha(alpha)
        _BRUSHES[key] = pg.mkBrush(colour)
    return _BRUSHES[key]


def configure_plot(plot: pg.PlotItem, title: str, x_label: str, y_label: str) -> None:
    """Title and axis labels (with units) in a readable size, a light grid."""
    plot.setTitle(title, size="10pt")
    plot.setLabel("bottom", x_label)
    plot.setLabel("left", y_label)
    plot.showGrid(x=True, y=True, alpha=0.25)
    for side in ("bottom", "left"):
        axis = plot.getAxis(side)
        axis.enableAutoSIPrefix(False)  # the label's unit stays what it says
        # pyqtgraph 0.14 still takes a scale from the axis's last range in that call: the next view
        # drawn showed 0.65 % residuals as 650 and Δxy 0.015 as 15000 on a second diagnosis.
        axis.autoSIPrefixScale, axis.labelUnitPrefix = 1.0, ""
        axis._updateLabel()
        axis.label.setFont(pg.QtGui.QFont("", 9))


class _Title(pg.LabelItem):
    """A plot's title that never widens its plot to fit the text: where the plot is narrower
    (four in a row on a 1366 × 768 screen) the title is cut. pyqtgraph's own title sets its
    minimum width to the text's, which widened the plot past its cell, and the plot beside it
    hid the right-hand side of its data."""

    def updateMin(self):
        super().updateMin()  # sets the text's size as the minimum and the size hints
        self.setMinimumWidth(0)
        height = self._sizeHint[Qt.SizeHint.MinimumSize][1]
        self._sizeHint[Qt.SizeHint.MinimumSize] = (0, height)
        self._sizeHint[Qt.SizeHint.PreferredSize] = (0, height)
        self.updateGeometry()


def emptiest_corner(points: list) -> tuple[int, int]:
    """The quarter of the plot that the fewest of ``points`` fall in: ``(right, bottom)``, 0 or 1.

    ``points``: (x, y) arrays of every series, in data coordinates (y up). Each is placed within
    the range of all of them; a quarter wins ties in the order top left, top right, bottom left,
    bottom right (the order ``counts`` is filled in). The legend goes there, so it covers as
    little of the data as it can.
    """
    xs = np.concatenate([np.asarray(x, float).ravel() for x, _ in points] or [np.zeros(0)])
    ys = np.concatenate([np.asarray(y, float).ravel() for _, y in points] or [np.zeros(0)])
    finite = np.isfinite(xs) & np.isfinite(ys)
    xs, ys = xs[finite], ys[finite]
    if xs.size == 0:
        return 0, 0
    x_mid = 0.5 * (xs.min() + xs.max())
    y_mid = 0.5 * (ys.min() + ys.max())
    counts = {(right, bottom): int(np.sum(((xs > x_mid) == bool(right))
                                          & ((ys < y_mid) == bool(bottom))))
              for bottom in (0, 1) for right in (0, 1)}
    return min(counts, key=counts.get)


def place_legend(legend: pg.LegendItem, right: int, bottom: int, margin: float = 5) -> None:
    """Anchor ``legend`` in a corner of its plot (``right``, ``bottom``: 0 or 1), ``margin``
    pixels in from both edges."""
    legend.anchor(itemPos=(right, bottom), parentPos=(right, bottom),
                  offset=(-margin if right else margin, -margin if bottom else margin))


class ViewPlot(pg.PlotWidget):
    """Shows one :class:`PlotView` at a time; a new view re-uses the curves of the last."""

    def __init__(self, parent=None, legend: bool = True):
        super().__init__(parent, background="w")
        self.setMinimumSize(220, 170)
        item = self.getPlotItem()  # its title, in the same place, replaced by one that never widens it
        item.layout.removeItem(item.titleLabel)
        item.scene().removeItem(item.titleLabel)
        item.titleLabel = _Title("", size="11pt", parent=item)
        item.layout.addItem(item.titleLabel, 0, 1)
        self._curves: list = []
        self._bars: list = []
        self._legend = item.addLegend(
            offset=(5, 5), labelTextSize="8pt", brush=None)  if legend else None
        self._empty = pg.TextItem("", color="#777", anchor=(0.5, 0.5))
        self.getPlotItem().addItem(self._empty, ignoreBounds=True)

    def _curve(self, i: int):
        while len(self._curves) <= i:
            curve = self.getPlotItem().plot([], [])
            self._curves.append(curve)
        return self._curves[i]

    def _bar(self, i: int):
        while len(self._bars) <= i:
            bar = pg.BarGraphItem(x=[], height=[], width=0.6)
            self.getPlotItem().addItem(bar)
            self._bars.append(bar)
        return self._bars[i]

    def show_view(self, view, empty_text: str = "no data") -> None:
        """Draw ``view`` (or clear the plot and say ``empty_text`` when it is None)."""
        plot = self.getPlotItem()
        if view is None:
            for curve in self._curves:
                curve.setData([], [])
            for bar in self._bars:
                bar.setOpts(x=[], height=[])
            self._empty.setText(empty_text)
            self._empty.setPos(0.5, 0.5)
            plot.setXRange(0, 1)
            plot.setYRange(0, 1)
            if self._legend is not None:
                self._legend.clear()
            return
        self._empty.setText("")
        configure_plot(plot, view.title, view.x_label, view.y_label)
        if self._legend is not None:
            self._legend.clear()
        bars = 0
        drawn = []
        for i, series in enumerate(view.series):
            curve = self._curve(i)
            x, y = np.asarray(series.x, float), np.asarray(series.y, float)
            drawn.append((x, y))
            if series.bars:
                bottom = min(0.0, float(y.min())) if len(y) and float(y.min()) < 50 else 0.9 * float(y.min())
                self._bar(bars).setOpts(x=x, height=y - bottom, y0=bottom, width=0.6, brush=brush(series.colour, 170),
                                        pen=pen(series.colour, 1))
                bars += 1
                curve.setData([], [])
                continue
            if series.points:
                curve.setData(x, y, pen=None, symbol="o", symbolSize=5, symbolPen=pen(series.colour, 1),
                              symbolBrush=brush(series.colour, 110))
            else:
                curve.setData(x, y, pen=pen(series.colour, 1.8, dashed=series.colour == 3), symbol=None)
            if self._legend is not None:
                self._legend.addItem(curve, series.name)
        for curve in self._curves[len(view.series):]:
            curve.setData([], [])
        for bar in self._bars[bars:]:
            bar.setOpts(x=[], height=[])
        if self._legend is not None:
            place_legend(self._legend, *emptiest_corner(drawn))
        plot.getAxis("bottom").setTicks([list(view.x_ticks)] if view.x_ticks else None)
        plot.enableAutoRange()
