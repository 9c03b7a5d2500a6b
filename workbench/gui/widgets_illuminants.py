"""Widgets of the Illuminants page: the source table model, the spectra plot, the ColorChecker swatches, the measure dialog."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import QAbstractTableModel, QModelIndex, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QFont, QPainter, QPen
from PySide6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QDoubleSpinBox,
    QFormLayout,
    QLineEdit,
    QSizePolicy,
    QWidget,
)

__all__ = ["SOURCE_COLUMNS", "SourceTableModel", "ColorCheckerSwatches", "MeasureLightDialog",
           "SpectraPlot", "SIMULATED_INSTRUMENT"]

SOURCE_COLUMNS = ("Id", "Name", "Kind", "CCT (K)", "Duv", "Rf", "Rg", "x", "y",
                  "Light RGB (headset)", "Light RGB (sRGB)")
"""Columns of the source table."""

CLIPPED_MARK = " *"
"""After a headset light RGB that is clipped (outside the headset's gamut; the tooltips say so): the
words "(clipped)" made the column so wide that the table scrolled sideways on a 1366 x 768 screen."""

SIMULATED_INSTRUMENT = "Simulated CS-2000 (emulator, white tile in a lightbooth)"

SORT_ROLE = Qt.ItemDataRole.UserRole + 1


def _rgb_text(rgb) -> str:
    return " ".join(f"{v:3d}" for v in rgb)


class SourceTableModel(QAbstractTableModel):
    """One :class:`workbench.illuminants.comparison.SourceRow` per row; rows arrive one by one."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self._rows = []
        self._index: dict[str, int] = {}

    # -- content --------------------------------------------------------------
    def put(self, row) -> None:
        """Add ``row``, or replace the row with its id."""
        if row.id in self._index:
            i = self._index[row.id]
            self._rows[i] = row
            self.dataChanged.emit(self.index(i, 0), self.index(i, len(SOURCE_COLUMNS) - 1))
            return
        i = len(self._rows)
        self.beginInsertRows(QModelIndex(), i, i)
        self._rows.append(row)
        self._index[row.id] = i
        self.endInsertRows()

    def ids(self) -> list[str]:
        return [row.id for row in self._rows]

    def rows(self) -> list:
        """The rows (:class:`~workbench.illuminants.comparison.SourceRow`), in the order added."""
        return list(self._rows)

    def row_of(self, source_id: str):
        i = self._index.get(source_id)
        return None if i is None else self._rows[i]

    # -- Qt -------------------------------------------------------------------
    def rowCount(self, parent=QModelIndex()):  # noqa: N802 - Qt's name
        return 0 if parent.isValid() else len(self._rows)

    def columnCount(self, parent=QModelIndex()):  # noqa: N802 - Qt's name
        return 0 if parent.isValid() else len(SOURCE_COLUMNS)

    def headerData(self, section, orientation, role=Qt.ItemDataRole.DisplayRole):  # noqa: N802
        if orientation == Qt.Orientation.Horizontal and role == Qt.ItemDataRole.DisplayRole:
            return SOURCE_COLUMNS[section].replace(" (", "\n(")  # two lines: narrower
        if orientation == Qt.Orientation.Horizontal and role == Qt.ItemDataRole.ToolTipRole:
            return {
                "Rf": "CIE 224:2017 colour fidelity index (100 = renders colours like the reference)",
                "Rg": "ANSI/IES TM-30-18 gamut index (100 = same saturation as the reference)",
                "Duv": "distance from the Planckian locus in CIE 1960 uv",
                "Light RGB (headset)": ("level-1 light colour (8-bit) for the current profile; "
                                        f"'{CLIPPED_MARK.strip()}': clipped, the light is outside the headset's gamut"),
                "Light RGB (sRGB)": "level-1 light colour (8-bit) for the ideal sRGB display",
            }.get(SOURCE_COLUMNS[section])
        return None

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        row = self._rows[index.row()]
        column = SOURCE_COLUMNS[index.column()]
        values = {
            "Id": row.id, "Name": row.name, "Kind": row.kind, "CCT (K)": row.CCT,
            "Duv": row.Duv, "Rf": row.Rf, "Rg": row.Rg, "x": row.xy[0], "y": row.xy[1],
            "Light RGB (headset)": row.rgb8_profile, "Light RGB (sRGB)": row.rgb8_srgb,
        }
        value = values[column]
        if role == Qt.ItemDataRole.DisplayRole:
            formats = {"CCT (K)": "{:.0f}", "Duv": "{:+.4f}", "Rf": "{:.1f}", "Rg": "{:.1f}",
                       "x": "{:.4f}", "y": "{:.4f}"}
            if column in formats:
                return formats[column].format(value)
            if column.startswith("Light RGB"):
                text = _rgb_text(value)
                if column == "Light RGB (headset)" and not row.light_in_gamut:
                    text += CLIPPED_MARK
                return text
            return str(value)
        if role == SORT_ROLE:
            if column.startswith("Light RGB"):
                return float(sum(value))
            return value if isinstance(value, (int, float)) else str(value).lower()
        if role == Qt.ItemDataRole.DecorationRole and column.startswith("Light RGB"):
            return QColor(*value)
        if role == Qt.ItemDataRole.TextAlignmentRole and column not in ("Id", "Name", "Kind"):
            return int(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        if role == Qt.ItemDataRole.ToolTipRole:
            if column == "Light RGB (headset)" and not row.light_in_gamut:
                return (f"{_rgb_text(value)}: clipped, {row.name} is outside the headset's gamut "
                        "(the nearest colour it can show)")
            return f"{row.name} ({row.kind}), id {row.id}"
        return None


class ColorCheckerSwatches(QWidget):
    """The 24 patches under each selected source: level 1 and level 2, each against its target.

    Each swatch shows the colour the patch should have under the source (top
    half) over what the headset shows (bottom half), with the CIEDE2000
    between them printed underneath.
    """

    CELL_MIN = 30

    def __init__(self, parent=None):
        super().__init__(parent)
        self._comparisons = []
        self._names: dict[str, str] = {}
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Preferred)

    def set_comparisons(self, comparisons, names: dict[str, str]) -> None:
        self._comparisons = list(comparisons)
        self._names = dict(names)
        self.updateGeometry()
        self.update()

    def _block_height(self) -> int:
        line = self.fontMetrics().height()
        return line + 2 * (34 + line + 4) + 6

    def sizeHint(self):  # noqa: N802 - Qt's name
        return QSize(24 * 44 + 80, max(1, len(self._comparisons)) * self._block_height() + 4)

    def minimumSizeHint(self):  # noqa: N802 - Qt's name
        return QSize(24 * self.CELL_MIN + 80, self.sizeHint().height())

    def paintEvent(self, event):  # noqa: N802 - Qt's name
        painter = QPainter(self)
        painter.fillRect(self.rect(), self.palette().window())
        metrics = self.fontMetrics()
        line = metrics.height()
        label_w = metrics.horizontalAdvance("Level 2 ") + 8
        cell_w = max(self.CELL_MIN, (self.width() - label_w - 4) / 24.0)
        small = QFont(self.font())
        small.setPointSizeF(max(7.0, self.font().pointSizeF() * 0.85))
        if not self._comparisons:
            painter.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter,
                             "Select one or more light sources in the table")
        y = 2
        for comparison in self._comparisons:
            name = self._names.get(comparison.source, comparison.source)
            bold = QFont(self.font())
            bold.setBold(True)
            painter.setFont(bold)
            painter.setPen(self.palette().windowText().color())
            painter.drawText(QRectF(0, y, self.width(), line), Qt.AlignmentFlag.AlignLeft,
                             f"{name}: mean ΔE00 level 1 {comparison.level1_dE00.mean():.2f}, "
                             f"level 2 {comparison.level2_dE00.mean():.2f} "
                             "(top half: the patch under the source; bottom: what the headset shows)")
            y += line + 2
            for label, shown, dE in (("Level 1", comparison.level1_rgb8, comparison.level1_dE00),
                                     ("Level 2", comparison.level2_rgb8, comparison.level2_dE00)):
                painter.setFont(self.font())
                painter.setPen(self.palette().windowText().color())
                painter.drawText(QRectF(0, y, label_w, 34), Qt.AlignmentFlag.AlignVCenter, label)
                for i in range(24):
                    x = label_w + i * cell_w
                    rect = QRectF(x + 1, y, cell_w - 2, 34)
                    painter.fillRect(QRectF(rect.x(), rect.y(), rect.width(), 17),
                                     QColor(*(int(v) for v in comparison.target_rgb8[i])))
                    painter.fillRect(QRectF(rect.x(), rect.y() + 17, rect.width(), 17),
                                     QColor(*(int(v) for v in shown[i])))
                    painter.setPen(QPen(QColor(90, 90, 90)))
                    painter.drawRect(rect)
                    painter.setFont(small)
                    painter.setPen(self.palette().windowText().color())
                    painter.drawText(QRectF(x, y + 34, cell_w, line), Qt.AlignmentFlag.AlignHCenter,
                                     f"{dE[i]:.1f}")
                y += 34 + line + 4
            y += 6
        painter.end()


class MeasureLightDialog(QDialog):
    """Choose the instrument (a CS-2000 port or the simulated one) and name the light."""

    def __init__(self, source_ids, ports=(), parent=None):
        super().__init__(parent)
        self.setWindowTitle("Measure a light")
        self.instrument = QComboBox()
        self.instrument.addItem(SIMULATED_INSTRUMENT, None)
        for port, description in ports:
            self.instrument.addItem(f"CS-2000 on {port} ({description})", port)
        self.booth_source = QComboBox()
        for source_id in source_ids:
            self.booth_source.addItem(source_id, source_id)
        self.illuminance = QDoubleSpinBox()
        self.illuminance.setRange(10.0, 20000.0)
        self.illuminance.setValue(1000.0)
        self.illuminance.setSuffix(" lx")
        self.name = QLineEdit()
        self.name.setPlaceholderText("e.g. booth D65 tube, 2026-11-22")
        form = QFormLayout(self)
        form.addRow("Instrument:", self.instrument)
        form.addRow("Light in the simulated booth:", self.booth_source)
        form.addRow("Illuminance on the tile:", self.illuminance)
        form.addRow("Name in your library:", self.name)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok
                                   | QDialogButtonBox.StandardButton.Cancel)
        buttons.button(QDialogButtonBox.StandardButton.Ok).setText("Measure")
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)
        self.instrument.currentIndexChanged.connect(self._simulated_only)
        self._simulated_only()

    def _simulated_only(self) -> None:
        simulated = self.instrument.currentData() is None
        self.booth_source.setEnabled(simulated)
        self.illuminance.setEnabled(simulated)


class SpectraPlot(pg.PlotWidget):
    """Relative SPDs (each scaled to a maximum of 1) of the selected sources; one curve per source, reused."""

    COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
               "#17becf", "#7f7f7f", "#bcbd22")

    def __init__(self, parent=None):
        super().__init__(parent, background="w")
        self._curves: dict[str, pg.PlotDataItem] = {}
        self.setLabel("bottom", "Wavelength", units="nm")
        self.setLabel("left", "Relative spectral power (max = 1)")
        self.showGrid(x=True, y=True, alpha=0.25)
        self.setXRange(380, 780, padding=0.01)
        self.setYRange(0, 1.05, padding=0)
        for name in ("bottom", "left"):
            axis = self.getPlotItem().getAxis(name)
            axis.setPen(pg.mkPen("#444"))
            axis.setTextPen(pg.mkPen("#111"))
            axis.enableAutoSIPrefix(False)
        self.setTitle("Spectra of the selected sources", color="#111", size="10pt")
        self.legend = self.addLegend(offset=(10, 10), labelTextSize="9pt", labelTextColor="#111",
                                     brush=pg.mkBrush(255, 255, 255, 200))
        self.setMinimumHeight(220)

    def curve(self, source_id: str):
        """The curve of ``source_id`` (None if it was never shown)."""
        return self._curves.get(source_id)

    def show_sources(self, illuminants) -> None:
        """Show exactly these sources, in this order (colours by position)."""
        ids = [illuminant.id for illuminant in illuminants]
        for source_id, curve in self._curves.items():
            self.legend.removeItem(curve)
            if source_id not in ids:
                curve.hide()
        for i, illuminant in enumerate(illuminants):
            values = np.asarray(illuminant.sd.values, dtype=float)
            peak = values.max()
            curve = self._curves.get(illuminant.id)
            if curve is None:
                curve = self.plot()
                self._curves[illuminant.id] = curve
            self.legend.addItem(curve, illuminant.name)
            curve.setPen(pg.mkPen(self.COLOURS[i % len(self.COLOURS)], width=2))
            curve.setData(illuminant.sd.wavelengths, values / peak if peak > 0 else values)
            curve.show()
