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
