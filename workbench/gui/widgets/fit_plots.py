"""The Fit & diagnose page's plots: sweep fits and residuals, additivity, chromaticity, white references."""

from __future__ import annotations

from PySide6.QtWidgets import QGridLayout, QWidget

from workbench.gui import diagnosis_views as views
from workbench.gui.widgets.plot_view import ViewPlot

__all__ = ["FitPlots"]


class FitPlots(QWidget):
    """Three columns of sweep fit over residuals, then additivity, greys, chromaticity and white references."""

    def __init__(self, parent=None):
        super().__init__(parent)
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        self.fits = [ViewPlot() for _ in range(3)]
        self.residuals = [ViewPlot() for _ in range(3)]
        for c in range(3):
            grid.addWidget(self.fits[c], 0, c)
            grid.addWidget(self.residuals[c], 1, c)
        self.additivity = ViewPlot(legend=False)
        self.greys = ViewPlot(legend=False)
        self.chromaticity = ViewPlot()
        self.whites = ViewPlot(legend=False)
        bottom = QGridLayout()
        for column, plot in enumerate((self.additivity, self.greys, self.chromaticity, self.whites)):
            bottom.addWidget(plot, 0, column)
        grid.addLayout(bottom, 2, 0, 1, 3)

    def plots(self) -> list:
        return [*self.fits, *self.residuals, self.additivity, self.greys, self.chromaticity, self.whites]

    def show_diagnosis(self, diagnosis) -> None:
        """Plot ``diagnosis`` (None: empty plots that say why)."""
        for _ in self.drawing_steps(diagnosis):
            pass

    def drawing_steps(self, diagnosis):
        """:meth:`show_diagnosis` a part at a time: a generator that yields after the sweeps'
        views are computed and after each plot, so that a page can draw each part, and repaint
        it, in an event-loop turn of its own (a plot's first paint after new data is 30–45 ms)."""
        if diagnosis is None:
            for plot in self.plots():
                plot.show_view(None, "open a session or calibrate")
            return
        sweeps = views.sweep_views(diagnosis)
        yield
        for c, sweep in enumerate(sweeps):
            self.fits[c].show_view(sweep.fit)
            yield
            self.residuals[c].show_view(sweep.residuals)
            yield
        self.additivity.show_view(views.additivity_view(diagnosis))
        yield
        greys = views.grey_additivity_view(diagnosis)
        self.greys.setVisible(greys is not None)
        self.greys.show_view(greys, "no greys measured")
        yield
        self.chromaticity.show_view(views.chromaticity_view(diagnosis))
        yield
        self.whites.show_view(views.white_reference_view(diagnosis),
                              "white references need times\n(fewer than 3, or none in this file)")
