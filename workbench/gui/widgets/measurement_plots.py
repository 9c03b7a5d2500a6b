"""The Calibrate page's live plots: the three channel sweeps and the white references, point by point."""

from __future__ import annotations

import pyqtgraph as pg
from PySide6.QtWidgets import QGridLayout, QWidget

from workbench.gui.widgets.plot_view import brush, configure_plot, pen

__all__ = ["MeasurementPlots", "SWEEP_KINDS"]

SWEEP_KINDS = ("ramp-r", "ramp-g", "ramp-b")
_NAMES = ("red", "green", "blue")


class MeasurementPlots(QWidget):
    """Luminance vs DAC for each channel's sweep, and the white references' luminance vs session time.

    Each plot has one curve, created once; :meth:`add` appends a point and
    ``setData``-s it.
    """

    def __init__(self, parent=None):
        super().__init__(parent)
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        self.plots: dict = {}
        self._data: dict = {}
        self._curves: dict = {}
        for i, kind in enumerate(SWEEP_KINDS):
            self._add_plot(kind, f"{_NAMES[i]} sweep", "DAC", "luminance Lv, cd/m²", i, 0, i)
        self._add_plot("white", "white references", "session time, min", "luminance Lv, cd/m²", 3, 0, 3)

    def _add_plot(self, key, title, x_label, y_label, colour, row, column):
        widget = pg.PlotWidget(background="w")
        widget.setMinimumSize(200, 160)
        configure_plot(widget.getPlotItem(), title, x_label, y_label)
        self._curves[key] = widget.getPlotItem().plot([], [], pen=pen(colour, 1.2), symbol="o", symbolSize=6,
                                                     symbolPen=pen(colour, 1), symbolBrush=brush(colour, 150))
        self._data[key] = ([], [])
        self.plots[key] = widget
        self.layout().addWidget(widget, row, column)

    def clear(self) -> None:
        for key, curve in self._curves.items():
            self._data[key] = ([], [])
            curve.setData([], [])

    def add(self, record) -> None:
        """Add a journal record's point to the plot of its kind (sweeps and whites; others are ignored)."""
        if not record.ok:
            return
        if record.kind in SWEEP_KINDS:
            key, x = record.kind, float(record.rgb[SWEEP_KINDS.index(record.kind)])
        elif record.kind == "white":
            key, x = "white", record.t_s / 60
        else:
            return
        xs, ys = self._data[key]
        xs.append(x)
        ys.append(float(record.Lv))
        order = sorted(range(len(xs)), key=xs.__getitem__)
        self._curves[key].setData([xs[i] for i in order], [ys[i] for i in order])

    def point_counts(self) -> dict:
        """Points shown per plot."""
        return {key: len(xs) for key, (xs, ys) in self._data.items()}
