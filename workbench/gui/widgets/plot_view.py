"""A pyqtgraph plot that shows a :class:`~workbench.gui.diagnosis_views.PlotView`, updated in place.

Curves are created once, on the first view that needs them, and later views
only ``setData`` them; pens and brushes are made once per colour.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor

__all__ = ["PALETTE", "pen", "brush", "ViewPlot", "configure_plot", "emptiest_corner", "place_legend",
           "LegendRoom", "legend_room", "MAX_LEGEND_ROOM", "MIN_TITLE_PT", "SpacedAxis"]

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


LABEL_GAP = 0.5
"""The least gap between two x-axis tick labels, as a share of the widest label's width."""


def _coarser(spacing: float) -> tuple[float, float]:
    """The next tick spacing of the 1, 2, 5 × 10ⁿ series above ``spacing``, and its minor one."""
    unit = 10.0 ** np.floor(np.log10(spacing))
    mantissa = round(spacing / unit)
    if mantissa < 2:
        return 2 * unit, unit
    if mantissa < 5:
        return 5 * unit, unit
    return 10 * unit, 2 * unit


class SpacedAxis(pg.AxisItem):
    """An x axis whose major tick labels leave gaps between them (:data:`LABEL_GAP`).

    pyqtgraph chooses the major spacing from the axis's range and length alone and always labels
    every major tick: a DAC axis of 220 units on a 105-pixel plot (five plots in a row on a
    1366 × 768 screen) got a major tick every 50 and read "100150200". Here the spacing grows
    along 1, 2, 5 × 10ⁿ until the labels fit, with the minor ticks of the spacing chosen."""

    def tickSpacing(self, minVal, maxVal, size):
        levels = super().tickSpacing(minVal, maxVal, size)
        if (not levels or self._tickSpacing is not None or size <= 0 or maxVal <= minVal
                or levels[0][0] <= 0 or self.orientation not in ("bottom", "top")):
            return levels
        metrics = pg.QtGui.QFontMetricsF(self.style["tickFont"] or self.font())
        major, chosen = float(levels[0][0]), levels
        while True:
            values = np.arange(np.ceil(minVal / major), np.floor(maxVal / major) + 1) * major
            if values.size < 2:
                return chosen
            widest = max(metrics.horizontalAdvance(text)
                         for text in self.tickStrings(list(values), self.scale, major))
            if major / (maxVal - minVal) * size >= (1.0 + LABEL_GAP) * widest:
                return chosen
            major, minor = _coarser(major)
            chosen = [(major, 0.0), (minor, 0.0)]


MIN_TITLE_PT = 7.5
"""The smallest font a plot's title shrinks to where its plot is narrower than the title; past
that it is shortened with an ellipsis and the whole title is the tooltip."""


class _Title(pg.LabelItem):
    """A plot's title that never widens its plot to fit the text. pyqtgraph's own title sets its
    minimum width to the text's, which widened the plot past its cell, and the plot beside it hid
    the right-hand side of its data. Where the plot is narrower than the title (five in a row on
    a 1366 × 768 screen) the title is drawn in a smaller font, down to :data:`MIN_TITLE_PT`, and
    past that shortened with "…" (the whole title in its tooltip): cut at the plot's edge, "greys
    / sum of channels" had read "greys / sum of chann"."""

    def setText(self, text, **args):
        self._wanted = (str(text), dict(args))
        self._fitted = None
        self._fit()

    def resizeEvent(self, ev):
        self._fit()
        super().resizeEvent(ev)

    def _fit(self) -> None:
        """Draw the wanted title in the largest font from its own size down to
        :data:`MIN_TITLE_PT` that fits the width it has, else elided at that size."""
        text, args = self._wanted  # LabelItem's constructor sets the first text
        width = float(self.size().width())
        if self._fitted == (text, width):
            return
        self._fitted = (text, width)
        size = str(args.get("size", self.opts.get("size", "11pt")))
        largest = float(size[:-2]) if size.endswith("pt") else 11.0
        sizes = [largest, *np.arange(largest - 0.5, MIN_TITLE_PT - 0.01, -0.5)]
        shown = text
        for pt in sizes:
            super().setText(text, **{**args, "size": f"{pt:g}pt"})
            if width <= 0 or self.item.boundingRect().width() <= width:
                break
        else:  # too wide even at the smallest size: as many characters as fit, then "…"
            smallest = {**args, "size": f"{sizes[-1]:g}pt"}
            low, high = 0, len(text)
            while low < high:
                middle = (low + high + 1) // 2
                super().setText(text[:middle].rstrip() + "…", **smallest)
                fits = self.item.boundingRect().width() <= width
                low, high = (middle, high) if fits else (low, middle - 1)
            shown = text[:low].rstrip() + "…"
            super().setText(shown, **smallest)
        self.setToolTip(text if shown != text else "")

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
    bottom right (the order :func:`_quarter_counts` fills them in). A legend too large for its
    plot to make room for (:func:`legend_room`) goes there, so it covers as little of the data as
    it can; :func:`legend_room` breaks its own ties by it.
    """
    xs, ys = _finite(points)
    if xs.size == 0:
        return 0, 0
    counts = _quarter_counts(xs, ys)
    return min(counts, key=counts.get)


def _finite(points: list) -> tuple[np.ndarray, np.ndarray]:
    """Every series' finite points, as two flat arrays."""
    xs = np.concatenate([np.asarray(x, float).ravel() for x, _ in points] or [np.zeros(0)])
    ys = np.concatenate([np.asarray(y, float).ravel() for _, y in points] or [np.zeros(0)])
    finite = np.isfinite(xs) & np.isfinite(ys)
    return xs[finite], ys[finite]


def _quarter_counts(xs: np.ndarray, ys: np.ndarray) -> dict:
    """Points in each quarter of their range, by ``(right, bottom)``, filled in the order top
    left, top right, bottom left, bottom right."""
    x_mid = 0.5 * (xs.min() + xs.max())
    y_mid = 0.5 * (ys.min() + ys.max())
    return {(right, bottom): int(np.sum(((xs > x_mid) == bool(right)) & ((ys < y_mid) == bool(bottom))))
            for bottom in (0, 1) for right in (0, 1)}


MAX_LEGEND_ROOM = 1.0
"""The most a plot's y range grows (as a share of the data's own) to clear its legend; a legend
that needs more is larger than the plot can give it, and goes where the fewest points are."""


@dataclass(frozen=True)
class LegendRoom:
    """Where a plot's legend goes and the ranges that keep the data out from under it."""

    corner: tuple[int, int]  # (right, bottom), 0 or 1, as :func:`place_legend` takes it
    x_range: tuple[float, float]
    y_range: tuple[float, float]
    growth: float  # how much the y range grew for it, as a share of the data's padded range


def _padded(values: np.ndarray, pad: float) -> tuple[float, float]:
    low, high = float(values.min()), float(values.max())
    span = high - low
    if span <= 0:
        span = abs(low) * 0.1 or 1.0
        return low - span / 2, high + span / 2
    return low - pad * span, high + pad * span


def legend_room(points: list, fraction: tuple[float, float], pad: float = 0.04) -> LegendRoom | None:
    """The corner whose legend needs the least extra y range to cover none of ``points``, and the ranges.

    ``points``: (x, y) arrays in data coordinates (y up), every point a series draws, lines
    sampled along their length. ``fraction``: the legend's width and height (with its margin) as
    shares of the data area's. The x range is the data's, padded by ``pad`` of its span each side;
    the y range too, then widened on the legend's side until every point under the legend's
    columns lies below (or above) it. The corner needing the least growth wins; of equals, the
    quarter with the fewest points (:func:`emptiest_corner`'s order). None where there are no
    points, or where even the best corner needs more than :data:`MAX_LEGEND_ROOM` (the legend
    does not fit).

    Autoranged, pyqtgraph draws the data edge to edge, and a legend anchored in the emptiest
    quarter still covered points wherever no quarter was empty (the residual plots' scatter, the
    sweeps' curves under a four-entry legend on a 1366 × 768 screen).
    """
    xs, ys = _finite(points)
    fx, fy = fraction
    if xs.size == 0 or not (0 < fx < 1 and 0 < fy < 1):
        return None
    x0, x1 = _padded(xs, pad)
    y0, y1 = _padded(ys, pad)
    best = None
    # the quarters with the fewest points first (a stable sort keeps top left, top right, bottom
    # left, bottom right among equals): a tie in growth goes to the emptier quarter
    for (right, bottom), _ in sorted(_quarter_counts(xs, ys).items(), key=lambda item: item[1]):
        edge = x1 - fx * (x1 - x0) if right else x0 + fx * (x1 - x0)
        under = ys[(xs >= edge) if right else (xs <= edge)]
        low, high = y0, y1
        if under.size and not bottom:  # the legend's lower edge, y1 - fy (y1 - y0), above them all
            high = max(y1, (float(under.max()) - fy * y0) / (1 - fy))
        elif under.size:  # its upper edge, y0 + fy (y1 - y0), below them all
            low = min(y0, (float(under.min()) - fy * y1) / (1 - fy))
        growth = (high - low) / (y1 - y0) - 1.0
        if best is None or growth < best.growth - 1e-9:
            best = LegendRoom((right, bottom), (x0, x1), (low, high), growth)
    return best if best.growth <= MAX_LEGEND_ROOM else None


def place_legend(legend: pg.LegendItem, right: int, bottom: int, margin: float = 5) -> None:
    """Anchor ``legend`` in a corner of its plot (``right``, ``bottom``: 0 or 1), ``margin``
    pixels in from both edges."""
    legend.anchor(itemPos=(right, bottom), parentPos=(right, bottom),
                  offset=(-margin if right else margin, -margin if bottom else margin))


class _CompactSample(pg.ItemSample):
    """A legend entry's sample in a row as tall as its 8-point label: pyqtgraph's is 20 pixels
    square, and four entries filled most of a small plot's height."""

    HEIGHT = 14

    def __init__(self, item):
        super().__init__(item)
        self.setFixedHeight(self.HEIGHT)

    def boundingRect(self):
        return pg.QtCore.QRectF(0, 0, 20, self.HEIGHT)

    def paint(self, p, *args):
        p.translate(0, self.HEIGHT / 2 - 10)  # pyqtgraph draws the sample about y = 10
        super().paint(p, *args)


def _compact(label: pg.LabelItem) -> None:
    """A legend label without the text document's 4-pixel margin round it."""
    label.item.document().setDocumentMargin(0)
    label.setText(label.text)  # sizes it again
    label.setMaximumHeight(label.minimumHeight())


class ViewPlot(pg.PlotWidget):
    """Shows one :class:`PlotView` at a time; a new view re-uses the curves of the last."""

    def __init__(self, parent=None, legend: bool = True):
        super().__init__(parent, background="w", axisItems={"bottom": SpacedAxis("bottom")})
        self.setMinimumSize(220, 170)
        item = self.getPlotItem()  # its title, in the same place, replaced by one that never widens it
        item.layout.removeItem(item.titleLabel)
        item.scene().removeItem(item.titleLabel)
        item.titleLabel = _Title("", size="11pt", parent=item)
        item.layout.addItem(item.titleLabel, 0, 0, 1, 3)  # over the axes too: room for more of it
        self._curves: list = []
        self._bars: list = []
        self._legend = item.addLegend(
            offset=(5, 5), labelTextSize="8pt", brush=None, sampleType=_CompactSample) if legend else None
        if self._legend is not None:
            # no box is drawn round it, so its margins only took room from the data
            self._legend.layout.setContentsMargins(0, 0, 0, 0)
        self._empty = pg.TextItem("", color="#777", anchor=(0.5, 0.5))
        self.getPlotItem().addItem(self._empty, ignoreBounds=True)
        self._room_points: list | None = None  # what the legend must not cover, as last drawn
        # the legend's share of the plot changes with the plot's size: its room with it, until
        # the user pans or zooms (their range is kept)
        box = self.getPlotItem().getViewBox()
        box.sigResized.connect(self._fit_range)
        box.sigRangeChangedManually.connect(self._keep_users_range)

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
            self._room_points = None
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
            drawn.append(_along(x, y) if not (series.points or series.bars) else (x, y))
            if series.bars:
                bottom = min(0.0, float(y.min())) if len(y) and float(y.min()) < 50 else 0.9 * float(y.min())
                self._bar(bars).setOpts(x=x, height=y - bottom, y0=bottom, width=0.6, brush=brush(series.colour, 170),
                                        pen=pen(series.colour, 1))
                bars += 1
                curve.setData([], [])
                # a bar covers its width from its bottom to its top
                drawn[-1] = (np.concatenate([x - 0.3, x + 0.3] * 2),
                             np.concatenate([y, y, np.full(y.size, bottom), np.full(y.size, bottom)]))
                continue
            if series.points:
                curve.setData(x, y, pen=None, symbol="o", symbolSize=5, symbolPen=pen(series.colour, 1),
                              symbolBrush=brush(series.colour, 110))
            else:
                curve.setData(x, y, pen=pen(series.colour, 1.8, dashed=series.colour == 3), symbol=None)
            if self._legend is not None:
                self._legend.addItem(curve, series.name)
                _compact(self._legend.items[-1][1])
        if self._legend is not None:  # its size from the compacted rows, once they are all in
            self._legend.layout.activate()
            self._legend.updateSize()
        for curve in self._curves[len(view.series):]:
            curve.setData([], [])
        for bar in self._bars[bars:]:
            bar.setOpts(x=[], height=[])
        plot.getAxis("bottom").setTicks([list(view.x_ticks)] if view.x_ticks else None)
        self._room_points = drawn
        self._fit_range()

    def _keep_users_range(self, *_) -> None:
        self._room_points = None

    def _fit_range(self, *_) -> None:
        """The data's range with room for the legend in the corner that needs the least
        (:func:`legend_room`), or autoranged with the legend where the fewest points are."""
        if self._room_points is None:
            return
        box = self.getPlotItem().getViewBox()
        room = None
        if self._legend is not None and self._legend.items and box.width() > 0 and box.height() > 0:
            size = self._legend.boundingRect()
            clearance = LEGEND_MARGIN + SYMBOL_RADIUS
            room = legend_room(self._room_points, ((size.width() + clearance) / box.width(),
                                                   (size.height() + clearance) / box.height()))
        if room is None:
            box.enableAutoRange()
            corner = emptiest_corner(self._room_points)
        else:
            box.setRange(xRange=room.x_range, yRange=room.y_range, padding=0)
            corner = room.corner
        if self._legend is not None:
            place_legend(self._legend, *corner, margin=LEGEND_MARGIN)


LEGEND_MARGIN = 5
"""Pixels between a plot's legend and the edges of its data area."""
SYMBOL_RADIUS = 4
"""Pixels a point's symbol reaches beyond the point (5-pixel symbols, with their outline)."""


def _along(x: np.ndarray, y: np.ndarray, samples: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """A line's points along its length where ``x`` rises (a curve over drive or time): the
    legend must clear the segments between the vertices, not only the vertices."""
    if x.size < 2 or not np.all(np.diff(x) >= 0):
        return x, y
    along = np.linspace(x[0], x[-1], samples)
    return np.concatenate([x, along]), np.concatenate([y, np.interp(along, x, y)])
