"""The plots put their legend in the quarter the data leave emptiest."""

import numpy as np
import pytest

from workbench.gui.diagnosis_views import PlotView, Series
from workbench.gui.widgets.plot_view import ViewPlot, emptiest_corner

DRIVE = np.linspace(0.0, 1.0, 52)


@pytest.mark.parametrize("y, corner", [
    (DRIVE ** 2.2, (0, 0)),        # a tone curve: rises late, the top left is empty
    (DRIVE ** 0.3, (1, 1)),        # rises early and flattens: the bottom right
    (1 - DRIVE ** 2.2, (0, 1)),    # falls late: the bottom left
    (np.zeros(52), (0, 1)),        # flat: counted in the top half; the bottom left, first of the ties
])
def test_the_emptiest_quarter(y, corner):
    assert emptiest_corner([(DRIVE * 255, y)]) == corner


def test_points_of_every_series_count_and_empty_series_are_ignored():
    rising = (DRIVE * 255, DRIVE ** 2.2)
    shoulder = (DRIVE[:20] * 255, np.full(20, 0.95))  # points in the top left too
    assert emptiest_corner([rising, shoulder, (np.array([]), np.array([]))]) == (1, 1)
    assert emptiest_corner([]) == (0, 0)


def test_the_legend_is_drawn_where_the_data_leave_room(qtbot):
    plot = ViewPlot()
    qtbot.addWidget(plot)
    plot.resize(400, 300)
    plot.show()
    for y, left, top in ((DRIVE ** 2.2, True, True), (DRIVE ** 0.3, False, False)):
        view = PlotView("sweep", "DAC", "output", (Series("measured", DRIVE * 255, y, 0),
                                                   Series("fit", DRIVE * 255, y, 0, points=False)))
        plot.show_view(view)
        qtbot.wait(50)
        box = plot.getPlotItem().vb.sceneBoundingRect()
        legend = plot._legend.sceneBoundingRect()
        assert (legend.center().x() < box.center().x()) is left
        assert (legend.center().y() < box.center().y()) is top


def test_a_long_title_does_not_widen_a_narrow_plot_past_its_cell(qtbot):
    plot = ViewPlot()
    qtbot.addWidget(plot)
    plot.setMinimumWidth(150)
    plot.resize(170, 180)
    plot.show()
    view = PlotView("chromaticity vs drive, every channel", "DAC", "Δxy from full drive",
                    (Series("red", DRIVE * 255, DRIVE, 0),))
    plot.show_view(view)
    qtbot.wait(100)
    # the data area and its axis stay within the widget, so nothing beside it hides them
    assert plot.getPlotItem().sceneBoundingRect().width() <= plot.width() + 0.5
    assert plot.getPlotItem().titleLabel.item.toPlainText().startswith("chromaticity vs drive")


def _under(room, fraction, xs, ys):
    """Points of (xs, ys) under a legend of ``fraction`` of the plot in ``room``'s corner."""
    (x0, x1), (y0, y1) = room.x_range, room.y_range
    right, bottom = room.corner
    fx, fy = fraction
    in_x = xs > x1 - fx * (x1 - x0) if right else xs < x0 + fx * (x1 - x0)
    in_y = ys < y0 + fy * (y1 - y0) - 1e-12 if bottom else ys > y1 - fy * (y1 - y0) + 1e-12
    return int(np.sum(in_x & in_y))


def test_the_legend_gets_room_where_no_quarter_is_empty():
    from workbench.gui.widgets.plot_view import legend_room

    rng = np.random.default_rng(7)
    x = np.arange(5.0, 256.0, 5.0)
    scatter = [(x, rng.normal(0.0, 0.1, x.size)), (x, rng.normal(0.0, 0.1, x.size))]
    xs, ys = np.concatenate([x, x]), np.concatenate([y for _, y in scatter])
    growths = []
    for fraction in ((0.5, 0.3), (0.3, 0.2), (0.8, 0.45)):
        room = legend_room(scatter, fraction)
        assert _under(room, fraction, xs, ys) == 0
        assert room.y_range[0] <= ys.min() and room.y_range[1] >= ys.max()
        growths.append(room.growth)
    assert max(growths) > 0.1  # the scatter fills every quarter: room was made for the legends
    # a tone curve leaves the top left empty: no room needed, and the legend goes there
    room = legend_room([(DRIVE * 255, DRIVE ** 2.2)], (0.4, 0.3))
    assert room.corner == (0, 0) and room.growth == 0
    # a legend as tall as the plot cannot be given room without hiding the data: none
    assert legend_room(scatter, (0.9, 0.8)) is None
    assert legend_room([], (0.3, 0.3)) is None


@pytest.mark.parametrize("size", [(230, 175), (420, 300)])  # a 1366 × 768 screen's cell, and larger
def test_the_legend_covers_no_point_of_a_scatter(qtbot, size):
    from PySide6.QtWidgets import QApplication

    plot = ViewPlot()
    qtbot.addWidget(plot)
    plot.resize(*size)
    plot.show()
    rng = np.random.default_rng(3)
    x = np.arange(5.0, 256.0, 5.0)
    view = PlotView("blue residuals", "DAC", "residual, % of full drive",
                    (Series("baseline", x, rng.normal(0, 0.1, x.size), 3),
                     Series("extended", x, rng.normal(0, 0.1, x.size), 2)))
    plot.show_view(view)
    qtbot.wait(50)
    for _ in range(5):
        QApplication.processEvents()
    box, legend = plot.getPlotItem().getViewBox(), plot._legend
    corners = [box.mapSceneToView(legend.mapToScene(point))
               for point in (legend.boundingRect().topLeft(), legend.boundingRect().bottomRight())]
    (x0, x1), (y0, y1) = sorted(c.x() for c in corners), sorted(c.y() for c in corners)
    assert x1 - x0 > 10 and y1 - y0 > 0.01  # drawn, on the plot
    for series in view.series:
        covered = (series.x > x0) & (series.x < x1) & (series.y > y0) & (series.y < y1)
        assert not covered.any(), series.name
    # its rows are as tall as their 8-point labels, not pyqtgraph's 20-pixel samples
    assert legend.boundingRect().height() <= 2 * 16


def test_a_resize_makes_room_again_but_keeps_a_range_the_user_chose(qtbot):
    plot = ViewPlot()
    qtbot.addWidget(plot)
    plot.resize(420, 300)
    plot.show()
    rng = np.random.default_rng(5)
    x = np.arange(5.0, 256.0, 5.0)
    plot.show_view(PlotView("residuals", "DAC", "residual", (Series("baseline", x, rng.normal(0, 0.1, x.size), 3),
                                                            Series("extended", x, rng.normal(0, 0.1, x.size), 2))))
    qtbot.wait(50)
    box = plot.getPlotItem().getViewBox()
    large = box.viewRange()[1]
    plot.resize(240, 180)  # the legend takes a larger share of a smaller plot: more room
    qtbot.wait(50)
    small = box.viewRange()[1]
    assert small[1] - small[0] > large[1] - large[0]
    box.setRange(xRange=(50, 100), yRange=(-0.05, 0.05), padding=0)
    box.sigRangeChangedManually.emit([True, True])  # as a pan or a zoom with the mouse does
    plot.resize(420, 300)
    qtbot.wait(50)
    assert np.allclose(box.viewRange()[1], (-0.05, 0.05))


def _shown(plot, view, qtbot):
    from PySide6.QtWidgets import QApplication

    plot.show_view(view)
    qtbot.wait(50)
    for _ in range(5):
        QApplication.processEvents()
    return plot.getPlotItem().titleLabel


def test_a_title_wider_than_its_plot_shrinks_then_is_shortened_with_its_whole_text_in_the_tooltip(qtbot):
    from workbench.gui.widgets.plot_view import MIN_TITLE_PT

    plot = ViewPlot()
    qtbot.addWidget(plot)
    plot.resize(400, 200)
    plot.show()
    series = (Series("red", DRIVE * 255, DRIVE, 0),)
    title = _shown(plot, PlotView("greys / sum of channels", "DAC", "%", series), qtbot)
    assert title.item.toPlainText() == "greys / sum of channels" and title.toolTip() == ""
    wide = title.item.boundingRect().width()
    plot.setMinimumWidth(0)
    plot.resize(150, 200)  # narrower than the title at its own size
    qtbot.wait(50)
    # the whole title, in a smaller font, within the width its plot gives it
    assert title.item.toPlainText() == "greys / sum of channels"
    assert title.item.boundingRect().width() < wide
    assert title.item.boundingRect().width() <= title.size().width() + 0.5
    long = "chromaticity vs drive, every channel, black subtracted"
    title = _shown(plot, PlotView(long, "DAC", "Δxy", series), qtbot)
    text = title.item.toPlainText()
    assert text.endswith("…") and long.startswith(text[:-1]) and len(text) > 12
    assert title.opts["size"] == f"{MIN_TITLE_PT:g}pt"  # shortened only at the smallest size
    assert title.item.boundingRect().width() <= title.size().width() + 0.5
    assert title.toolTip() == long
    plot.resize(900, 200)  # room again: the whole title at its own size
    qtbot.wait(50)
    assert title.item.toPlainText() == long and title.opts["size"] == "10pt"
    assert title.toolTip() == ""


def _bottom_labels(plot):
    """The x axis's tick labels as drawn, left to right: (left edge, right edge in pixels, text)."""
    from PySide6.QtGui import QImage, QPainter

    axis = plot.getPlotItem().getAxis("bottom")
    image = QImage(10, 10, QImage.Format.Format_ARGB32)
    painter = QPainter(image)
    try:
        _, _, texts = axis.generateDrawSpecs(painter)
    finally:
        painter.end()
    return sorted((rect.left(), rect.right(), text) for rect, _, text in texts)


@pytest.mark.parametrize("width", [165, 185, 260, 420])
def test_the_x_axis_labels_of_a_narrow_plot_leave_gaps_between_them(qtbot, width):
    plot = ViewPlot()
    qtbot.addWidget(plot)
    plot.setMinimumWidth(0)
    plot.resize(width, 200)
    plot.show()
    x = np.arange(40.0, 241.0, 8.0)  # a range under 225 DAC: pyqtgraph put a major tick every 50
    _shown(plot, PlotView("chromaticity vs drive", "DAC", "Δxy from full drive",
                          (Series("red", x, 1e-4 * np.sqrt(x), 0),)), qtbot)
    labels = _bottom_labels(plot)
    assert len(labels) >= 2, labels
    gaps = [b[0] - a[1] for a, b in zip(labels, labels[1:])]
    widths = [right - left for left, right, _ in labels]
    assert min(gaps) >= 0.5 * max(widths), (labels, gaps)
