"""Gamut page: the headset's gamut on a chromaticity diagram, with the references and coverage figures.

Everything drawn comes from :mod:`workbench.gamut`: the spectral locus, the
current profile's gamut (the hull of its RGB cube through its model), the
sRGB / DCI-P3 / Rec. 2020 outlines, the other shipped profiles (and any
profile file added), and the validation colours of the open session
(measured vs predicted). Curves are created once and ``setData``-ed.
"""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QMessageBox,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gamut import (
    DIAGRAMS,
    LOCUS_LABELS_NM,
    REFERENCE_GAMUTS,
    display_gamut,
    gamut_coverage,
    reference_gamut,
    shipped_profile_gamuts,
    spectral_locus,
    to_diagram,
    validation_points,
)
from workbench.gui.refresh import RedrawWhenShown
from workbench.gui.widgets.plot_view import place_legend

__all__ = ["GamutPage"]

_REFERENCE_PENS = {"sRGB": ("#555555", Qt.PenStyle.DashLine),
                   "DCI-P3": ("#e07b00", Qt.PenStyle.DashLine),
                   "Rec. 2020": ("#2a7f2a", Qt.PenStyle.DashLine)}
_OVERLAY_COLOURS = ("#8c564b", "#9467bd", "#17becf", "#bcbd22")
_HEADSET_COLOUR = "#1f4fd6"

EXPLANATION = ("Covered: the share of each reference gamut's area that the headset can show "
               "(100 % = all of it). Relative area: the headset's gamut area over the "
               "reference's (above 100 % = larger, though it may still miss some of it). "
               "Areas are compared in the chosen diagram; u′v′ is the more perceptually uniform.")


def _closed(points: np.ndarray) -> np.ndarray:
    return np.vstack([points, points[:1]])


LEGEND_CORNER = {"xy": (1, 0), "u'v'": (1, 1)}
"""Where each diagram's legend goes, ``(right, bottom)``: the corner the spectral locus leaves
empty. In xy that is the top right, above the locus from 540 to 620 nm (at the bottom right the
legend covered the red corners of every gamut and the line of purples); in u′v′ the bottom right,
below the line of purples."""


class GamutPage(QWidget):
    """The current profile's gamut against sRGB, DCI-P3, Rec. 2020 and other profiles."""

    title = "Gamut"

    def __init__(self, workspace, parent=None):
        super().__init__(parent)
        self.workspace = workspace
        self._overlays = []  # (name, Gamut) from the shipped profiles and files added
        self._coverage = {}

        self.diagram_box = QComboBox()
        for diagram in DIAGRAMS:
            self.diagram_box.addItem({"xy": "CIE 1931 xy", "u'v'": "CIE 1976 u′v′"}[diagram],
                                     diagram)
        self.diagram_box.currentIndexChanged.connect(lambda _: self._redraw())
        self.reference_boxes = {}
        self.overlay_box = QCheckBox("Other profiles")
        self.overlay_box.setChecked(True)
        self.overlay_box.toggled.connect(lambda _: self._redraw())
        self.validation_box = QCheckBox("Validation colours")
        self.validation_box.setChecked(True)
        self.validation_box.toggled.connect(lambda _: self._redraw())
        self.add_profile_button = QPushButton("Overlay a profile…")
        self.add_profile_button.clicked.connect(self._ask_profile)

        self.plot = pg.PlotWidget(background="w")
        self.plot.setAspectLocked(True)
        self.plot.showGrid(x=True, y=True, alpha=0.2)
        self.plot.setMinimumSize(480, 420)
        for name in ("bottom", "left"):
            axis = self.plot.getPlotItem().getAxis(name)
            axis.setPen(pg.mkPen("#444"))
            axis.setTextPen(pg.mkPen("#111"))
            axis.enableAutoSIPrefix(False)
        self.legend = self.plot.addLegend(offset=(-10, -10), labelTextSize="9pt",
                                          labelTextColor="#111",
                                          brush=pg.mkBrush(255, 255, 255, 220))
        self._locus = self.plot.plot(pen=pg.mkPen("#000", width=1.5), name="Spectral locus")
        self._locus_labels = []
        for nm in LOCUS_LABELS_NM:
            label = pg.TextItem(f"{nm}", color="#333", anchor=(0.5, 0.5))
            self.plot.addItem(label)
            self._locus_labels.append((nm, label))
        self._references = {}
        for name in REFERENCE_GAMUTS:
            colour, style = _REFERENCE_PENS[name]
            self._references[name] = self.plot.plot(pen=pg.mkPen(colour, width=1.5, style=style),
                                                    name=name)
            box = QCheckBox(name)
            box.setChecked(True)
            box.toggled.connect(lambda _: self._redraw())
            self.reference_boxes[name] = box
        self._overlay_curves = []
        self._headset = self.plot.plot(pen=pg.mkPen(_HEADSET_COLOUR, width=2.5), name="Headset")
        self._measured = pg.ScatterPlotItem(size=7, pen=pg.mkPen("#000"), brush=pg.mkBrush("#000"))
        self._predicted = pg.ScatterPlotItem(size=8, pen=pg.mkPen("#d62728", width=1.5),
                                             brush=pg.mkBrush(None))
        self._errors = pg.PlotDataItem(pen=pg.mkPen("#d62728", width=1), connect="pairs")
        for item in (self._errors, self._measured, self._predicted):
            self.plot.addItem(item)

        self.table = QTableWidget(len(REFERENCE_GAMUTS), 2)
        self.table.setHorizontalHeaderLabels(["Covered (%)", "Relative area (%)"])
        self.table.setVerticalHeaderLabels(list(REFERENCE_GAMUTS))
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
        self.table.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.table.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.table.resizeRowsToContents()
        self.table.setFixedHeight(self.table.horizontalHeader().sizeHint().height()
                                  + sum(self.table.rowHeight(r) for r in range(3))
                                  + 2 * self.table.frameWidth() + 2)
        self.headline = QLabel()
        self.headline.setWordWrap(True)
        self.headline.setTextFormat(Qt.TextFormat.RichText)
        self.explanation = QLabel(EXPLANATION)
        self.explanation.setWordWrap(True)
        self.validation_label = QLabel()
        self.validation_label.setWordWrap(True)

        controls = QHBoxLayout()
        controls.addWidget(QLabel("Diagram:"))
        controls.addWidget(self.diagram_box)
        for box in self.reference_boxes.values():
            controls.addWidget(box)
        controls.addWidget(self.overlay_box)
        controls.addWidget(self.validation_box)
        controls.addWidget(self.add_profile_button)
        controls.addStretch(1)
        side = QVBoxLayout()
        side.addWidget(self.headline)
        side.addWidget(QLabel("<b>Coverage of the reference gamuts</b>"))
        side.addWidget(self.table)
        side.addWidget(self.explanation)
        side.addWidget(self.validation_label)
        side.addStretch(1)
        side_widget = QWidget()
        side_widget.setLayout(side)
        side_widget.setMaximumWidth(420)
        body = QHBoxLayout()
        body.addWidget(self.plot, 1)
        body.addWidget(side_widget)
        layout = QVBoxLayout(self)
        layout.addLayout(controls)
        layout.addLayout(body, 1)

        try:
            for path, gamut in shipped_profile_gamuts():
                self._overlays.append((path, gamut))
        except WorkbenchError as error:  # a broken shipped profile must not hide the page
            self.validation_label.setText(f"Shipped profiles not shown: {error}")
        self._redraw_when_shown = RedrawWhenShown(self, self._on_workspace)
        self._unsubscribe = [workspace.subscribe(event, lambda ws: self._redraw_when_shown())
                             for event in ("profile-changed", "session-changed",
                                           "diagnosis-changed")]
        self._on_workspace()

    # -- public ---------------------------------------------------------------
    @property
    def diagram(self) -> str:
        return self.diagram_box.currentData()

    def set_diagram(self, diagram: str) -> None:
        self.diagram_box.setCurrentIndex(self.diagram_box.findData(diagram))

    def coverage(self, reference: str):
        """The :class:`workbench.gamut.Coverage` of ``reference`` for the workspace's profile."""
        self._redraw_when_shown.flush()
        return self._coverage[reference]

    def add_profile_overlay(self, path) -> None:
        """Overlay the gamut of the profile file ``path``; an error dialog names a bad file."""
        from workbench.profile import load_profile

        try:
            profile = load_profile(path)
            gamut = display_gamut(profile.display_model(), profile.device.get("name") or str(path))
        except WorkbenchError as error:
            QMessageBox.critical(self, "Cannot overlay the profile", str(error))
            return
        self._overlays.append((path, gamut))
        self._redraw()

    def save_screenshot(self, path) -> None:
        """Write the page as PNG (``grab`` is faithful: no OpenGL)."""
        self._redraw_when_shown.flush()
        if not self.grab().save(str(path)):
            raise OSError(f"could not write {path}")

    # -- drawing ----------------------------------------------------------------
    def _on_workspace(self) -> None:
        profile = self.workspace.profile
        self._gamut = display_gamut(profile.display_model(),
                                    profile.device.get("name") or "headset")
        self._points = validation_points(self.workspace.diagnosis, self.workspace.session,
                                         profile.display_model())
        self._redraw()

    def _redraw(self) -> None:
        diagram = self.diagram
        x_label, y_label, _ = DIAGRAMS[diagram]
        self.plot.setLabel("bottom", f"{x_label} (chromaticity, unitless)")
        self.plot.setLabel("left", f"{y_label} (chromaticity, unitless)")
        wavelengths, locus = spectral_locus(diagram)
        self._locus.setData(*_closed(locus).T)
        centre = locus.mean(axis=0)
        for nm, label in self._locus_labels:
            i = int(np.argmin(np.abs(wavelengths - nm)))
            tangent = locus[min(i + 3, len(locus) - 1)] - locus[max(i - 3, 0)]
            normal = np.array([tangent[1], -tangent[0]]) / np.linalg.norm(tangent)
            if np.dot(normal, locus[i] - centre) < 0:
                normal = -normal  # outwards, away from the white region
            label.setPos(*(locus[i] + 0.035 * normal))
        for name, curve in self._references.items():
            visible = self.reference_boxes[name].isChecked()
            curve.setData(*_closed(reference_gamut(name).vertices(diagram)).T)
            curve.setVisible(visible)
        self._draw_overlays(diagram)
        self._headset.setData(*_closed(self._gamut.vertices(diagram)).T)
        self.legend.removeItem(self._headset)
        self.legend.addItem(self._headset, f"Headset: {self._gamut.name}")
        self._draw_validation(diagram)
        self._update_table(diagram)
        limits = (-0.05, 0.8, -0.05, 0.9) if diagram == "xy" else (-0.05, 0.7, -0.05, 0.65)
        self.plot.setXRange(limits[0], limits[1], padding=0)
        self.plot.setYRange(limits[2], limits[3], padding=0)
        place_legend(self.legend, *LEGEND_CORNER[diagram], margin=10)

    def _draw_overlays(self, diagram: str) -> None:
        current = self._gamut.xy
        shown = [(p, g) for p, g in self._overlays
                 if not (g.xy.shape == current.shape and np.allclose(g.xy, current))]
        while len(self._overlay_curves) < len(shown):
            colour = _OVERLAY_COLOURS[len(self._overlay_curves) % len(_OVERLAY_COLOURS)]
            curve = self.plot.plot(pen=pg.mkPen(colour, width=1.5, style=Qt.PenStyle.DotLine))
            self._overlay_curves.append(curve)
        for curve in self._overlay_curves:
            self.legend.removeItem(curve)
            curve.hide()
        if not self.overlay_box.isChecked():
            return
        for curve, (_, gamut) in zip(self._overlay_curves, shown):
            curve.setData(*_closed(gamut.vertices(diagram)).T)
            curve.show()
            self.legend.addItem(curve, f"Profile: {gamut.name}")

    def _draw_validation(self, diagram: str) -> None:
        points = self._points
        visible = points is not None and self.validation_box.isChecked()
        for item in (self._errors, self._measured, self._predicted):
            item.setVisible(visible)
            self.legend.removeItem(item)
        if visible:
            self.legend.addItem(self._measured, "Validation: measured")
            self.legend.addItem(self._predicted, "Validation: predicted")
        if points is None:
            self.validation_label.setText("Validation colours: open a session (File ▸ Open) or "
                                          "run a calibration to see measured vs predicted colours.")
            self._measured.setData([], [])
            self._predicted.setData([], [])
            self._errors.setData([], [])
            return
        from colour import xy_to_XYZ

        measured = to_diagram(xy_to_XYZ(points.measured_xy), diagram)
        predicted = to_diagram(xy_to_XYZ(points.predicted_xy), diagram)
        self._measured.setData(*measured.T)
        self._predicted.setData(*predicted.T)
        pairs = np.empty((2 * len(measured), 2))
        pairs[0::2], pairs[1::2] = measured, predicted
        self._errors.setData(*pairs.T)
        self.validation_label.setText(f"Validation colours: {len(points)} patches, measured "
                                      f"(black dots) vs predicted by the {points.model} "
                                      "(red rings), joined by a line.")

    def _update_table(self, diagram: str) -> None:
        self._coverage = {name: gamut_coverage(self._gamut, reference_gamut(name), diagram)
                          for name in REFERENCE_GAMUTS}
        for row, name in enumerate(REFERENCE_GAMUTS):
            coverage = self._coverage[name]
            for column, value in enumerate((coverage.covered_pct, coverage.relative_area_pct)):
                item = QTableWidgetItem(f"{value:.1f}")
                item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                self.table.setItem(row, column, item)
        srgb, p3, rec2020 = (self._coverage[n] for n in ("sRGB", "DCI-P3", "Rec. 2020"))
        self.headline.setText(
            f"<b>{self._gamut.name}</b> covers {srgb.covered_pct:.0f} % of sRGB, "
            f"{p3.covered_pct:.0f} % of DCI-P3 and {rec2020.covered_pct:.0f} % of Rec. 2020 "
            f"({'CIE 1931 xy' if diagram == 'xy' else 'CIE 1976 u′v′'} areas).")

    # -- dialogs and teardown -------------------------------------------------------
    def _ask_profile(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Overlay a profile", "",
                                              "Profiles (*.vrprofile.json *.json)")
        if path:
            self.add_profile_overlay(path)

    def shutdown(self) -> None:
        """Stop listening to the workspace (idempotent; the main window calls it at teardown)."""
        for unsubscribe in self._unsubscribe:
            try:
                unsubscribe()
            except ValueError:
                pass
        self._unsubscribe = []

    def closeEvent(self, event):  # noqa: N802 - Qt's name
        self.shutdown()
        super().closeEvent(event)
