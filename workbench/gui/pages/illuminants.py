"""Illuminants page: the library as a filterable, sortable table; SPDs; the ColorChecker at level 1 and 2.

The table's rows (CCT, Duv, Rf, Rg, xy, the level-1 light colour for the
current profile and for sRGB: :func:`workbench.illuminants.comparison.source_row`)
are computed in a worker (superqt's ``thread_worker``: a generator that yields
one row per source, so the window never waits on it and a progress bar counts
them in). Selecting rows sets :meth:`Workspace.set_selected_sources`; the SPD
plot and the ColorChecker swatches follow the workspace's selection. Import
(CSV, TM-27 XML), export, "measure a light" (a CS-2000, or the emulator
measuring a simulated lightbooth) and "two-peak metamer" add sources to the
persistent user library (:class:`workbench.illuminants.user_library.UserLibrary`).
"""

from __future__ import annotations

from PySide6.QtCore import QItemSelection, QItemSelectionModel, QSortFilterProxyModel, Qt, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QFileDialog,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QLineEdit,
    QMessageBox,
    QProgressBar,
    QPushButton,
    QScrollArea,
    QSplitter,
    QTableView,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gui.jobs import start_job
from workbench.gui.refresh import RedrawWhenShown
from workbench.gui.widgets_illuminants import (
    CLIPPED_MARK,
    SORT_ROLE,
    ColorCheckerSwatches,
    MeasureLightDialog,
    SourceTableModel,
    SpectraPlot,
)
from workbench.gui.workers import describe_error
from workbench.illuminants import list_illuminants, read_illuminant_file, write_illuminant_file
from workbench.illuminants.comparison import colorchecker_comparison, source_row
from workbench.illuminants.user_library import UserLibrary, resolve_illuminant

__all__ = ["IlluminantsPage"]

MEASURE_TIME_SCALE = 0.02
"""How long the simulated CS-2000 makes a measurement wait, as a fraction of the real timing."""

ID_WIDTH_TEXT = "cie-fl3-12"
"""The source table's id column is as wide as this (a longer id is elided; the tooltip has it)."""


class IlluminantsPage(QWidget):
    """Compare light sources: table, spectra, the ColorChecker under each at level 1 and level 2."""

    title = "Illuminants"

    rows_ready = Signal()
    """Every row of the table has its metrics (after a start or a profile change)."""
    source_added = Signal(str)
    """A source was added to the user library (its id)."""
    error_shown = Signal(str)
    """An error dialog was shown (its text)."""

    def __init__(self, workspace, parent=None, library: UserLibrary | None = None):
        super().__init__(parent)
        self.workspace = workspace
        self.library = library or UserLibrary()
        self._workers = []  # workbench.gui.jobs.Job
        self._comparisons: dict[str, tuple] = {}  # source id: (comparison, name) for the current profile
        self._syncing = False
        self.last_error: str | None = None

        # -- table ----------------------------------------------------------
        self.model = SourceTableModel(self)
        self.proxy = QSortFilterProxyModel(self)
        self.proxy.setSourceModel(self.model)
        self.proxy.setFilterCaseSensitivity(Qt.CaseSensitivity.CaseInsensitive)
        self.proxy.setFilterKeyColumn(-1)
        self.proxy.setSortRole(SORT_ROLE)
        self.table = QTableView()
        self.table.setModel(self.proxy)
        self.table.setSortingEnabled(True)
        self.table.sortByColumn(-1, Qt.SortOrder.AscendingOrder)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.ExtendedSelection)
        self.table.verticalHeader().setVisible(False)
        self.table.setWordWrap(False)
        self.table.verticalHeader().setDefaultSectionSize(self.fontMetrics().height() + 6)
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        # the id as wide as a CIE one, elided in the middle (whole in the tooltip; the longest
        # built-in ids took a quarter of the table, and the light RGB scrolled out of sight)
        header.setSectionResizeMode(0, QHeaderView.ResizeMode.Interactive)
        header.resizeSection(0, self.fontMetrics().horizontalAdvance(ID_WIDTH_TEXT) + 16)
        self.table.setTextElideMode(Qt.TextElideMode.ElideMiddle)
        header.setSectionResizeMode(1, QHeaderView.ResizeMode.Stretch)
        header.setMinimumSectionSize(40)
        self.table.selectionModel().selectionChanged.connect(self._on_table_selection)
        self.filter = QLineEdit()
        self.filter.setPlaceholderText("Filter: id, name, kind … (e.g. fl, led, measured)")
        self.filter.setClearButtonEnabled(True)
        self.filter.textChanged.connect(self._apply_filter)
        self.progress = QProgressBar()
        self.progress.setFormat("computing Rf, Rg, CCT … %v of %m sources")
        self.progress.setMaximumWidth(340)

        self.import_button = QPushButton("Import…")
        self.import_button.setToolTip("Add a CSV (wavelength,value) or IES TM-27 XML spectrum "
                                      "to your library")
        self.export_button = QPushButton("Export…")
        self.export_button.setToolTip("Write the first selected source as CSV or TM-27 XML")
        self.measure_button = QPushButton("Measure a light…")
        self.measure_button.setToolTip("Measure a light with the CS-2000 (or the emulator) and "
                                       "add it to your library")
        self.metamer_button = QPushButton("Two-peak metamer")
        self.metamer_button.setToolTip("Synthesize a blue + yellow LED source with the first "
                                       "selected source's white, and add it to your library")
        self.import_button.clicked.connect(self._ask_import)
        self.export_button.clicked.connect(self._ask_export)
        self.measure_button.clicked.connect(self._ask_measure)
        self.metamer_button.clicked.connect(self._metamer_of_selection)
        self.status = QLabel()

        # -- plot -----------------------------------------------------------
        self.plot = SpectraPlot()

        self.swatches = ColorCheckerSwatches()
        swatch_scroll = QScrollArea()
        swatch_scroll.setWidgetResizable(True)
        swatch_scroll.setWidget(self.swatches)

        # -- layout ---------------------------------------------------------
        buttons = QHBoxLayout()
        for button in (self.import_button, self.export_button, self.measure_button,
                       self.metamer_button):
            buttons.addWidget(button)
        buttons.addStretch(1)
        filter_row = QHBoxLayout()
        filter_row.addWidget(self.filter, 1)
        filter_row.addWidget(self.progress)
        top = QWidget()
        top_layout = QVBoxLayout(top)
        top_layout.setContentsMargins(0, 0, 0, 0)
        top_layout.addLayout(buttons)
        top_layout.addLayout(filter_row)
        top_layout.addWidget(self.table, 1)
        top_layout.addWidget(self.status)
        upper = QSplitter(Qt.Orientation.Horizontal)
        upper.addWidget(top)
        upper.addWidget(self.plot)
        upper.setStretchFactor(0, 3)
        upper.setStretchFactor(1, 2)
        self.upper_splitter = upper
        middle = QSplitter(Qt.Orientation.Vertical)
        middle.addWidget(upper)
        middle.addWidget(swatch_scroll)
        middle.setStretchFactor(0, 1)
        middle.setStretchFactor(1, 1)
        self.splitter = middle
        layout = QVBoxLayout(self)
        layout.addWidget(middle)

        # A new profile's rows and swatches are computed when the page is next shown: their
        # worker (0.3–0.6 s of Python, a signal a source), started as a calibration's session
        # was put into the window, held it up (bench gui, quick plan: largest stall 124–128 ms in
        # three runs with it, 84–138 ms, median 92, in six without).
        self._profile_when_shown = RedrawWhenShown(self, self._on_profile_changed)
        self._unsubscribe = [
            workspace.subscribe("sources-changed", lambda ws: self._on_sources_changed()),
            workspace.subscribe("profile-changed", lambda ws: self._profile_when_shown()),
        ]
        self._on_sources_changed()
        self._start_rows()

    # -- public ---------------------------------------------------------------
    @property
    def busy(self) -> bool:
        """Whether a worker (metrics, measurement) is still running."""
        return any(job.running for job in self._workers)

    def all_ids(self) -> list[str]:
        """Every source the table lists: the built-in library, then the user library."""
        return list_illuminants() + self.library.ids()

    def import_file(self, path) -> str | None:
        """Import a CSV / TM-27 spectrum into the user library; an error dialog names a bad file."""
        try:
            illuminant = read_illuminant_file(path)
        except WorkbenchError as error:
            self._show_error("Cannot import the spectrum", describe_error(error))
            return None
        return self._add_to_library(illuminant)

    def export_source(self, source_id: str, path) -> None:
        """Write ``source_id`` as CSV or TM-27 XML (by the suffix of ``path``)."""
        try:
            write_illuminant_file(resolve_illuminant(source_id, self.library), path)
        except WorkbenchError as error:
            self._show_error("Cannot export the spectrum", describe_error(error))
            return
        self.status.setText(f"Wrote {source_id} to {path}")

    def synthesize_metamer(self, source_id: str) -> str | None:
        """Add the two-peak metamer of ``source_id`` to the user library and select it."""
        from workbench.illuminants.metamers import two_peak_metamer

        try:
            metamer = two_peak_metamer(resolve_illuminant(source_id, self.library))
        except WorkbenchError as error:
            self._show_error("Cannot synthesize a metamer", describe_error(error))
            return None
        new_id = self._add_to_library(metamer)
        self.workspace.set_selected_sources([source_id, new_id])
        return new_id

    def measure_light(self, booth_source: str | None, name: str, *, port: str | None = None,
                      illuminance_lux: float = 1000.0):
        """Measure a light in a worker and add it to the user library (``source_added`` when done).

        ``port`` None: the CS-2000 emulator measures a white tile lit by
        ``booth_source`` in a simulated lightbooth; else the CS-2000 on ``port``
        measures whatever its tile is lit by.
        """
        from workbench.illuminants.light_measurement import (
            SimulatedLightBooth,
            measure_light,
            measure_light_simulated,
        )

        library = self.library
        name = name.strip() or (f"{booth_source} (measured)" if port is None else "measured light")

        def work():
            if port is None:
                booth = SimulatedLightBooth(resolve_illuminant(booth_source, library),
                                            illuminance_lux)
                return measure_light_simulated(booth, name, time_scale=MEASURE_TIME_SCALE)
            return measure_light(port, name)

        self.measure_button.setEnabled(False)
        self.status.setText(f"Measuring {name} …")
        worker = self._run(work, returned=self._on_measured)
        return worker

    def save_screenshot(self, path) -> None:
        """Write the page as PNG (``QWidget.grab`` shows it faithfully: no OpenGL here)."""
        self._profile_when_shown.flush()
        if not self.grab().save(str(path)):
            raise OSError(f"could not write {path}")

    # -- workers ------------------------------------------------------------------
    def _run(self, function, *, returned=None, yielded=None, generator=False):
        job = start_job(function, generator=generator, returned=returned, yielded=yielded,
                        errored=self._on_worker_error, finished=self._on_worker_finished)
        self._workers.append(job)
        return job.worker

    def _start_rows(self) -> None:
        for job in self._workers:
            if job.tag == "rows":
                job.quit()
        profile = self.workspace.profile
        display = profile.display_model()
        k = profile.k
        ids = self.all_ids()
        library = self.library
        self.progress.setRange(0, len(ids))
        self.progress.setValue(0)
        self._skipped = []
        self.progress.show()
        # A superseded job (quit above) may still deliver a row, and it ends after this one
        # starts: only the latest job's rows and end count.
        self._rows_run = run = getattr(self, "_rows_run", 0) + 1

        def rows():
            for i, source_id in enumerate(ids):
                try:
                    row = source_row(resolve_illuminant(source_id, library), display, k=k)
                except WorkbenchError as error:  # e.g. a user-library file edited by hand
                    row = f"{source_id}: {describe_error(error)}"
                yield run, i + 1, row

        worker = self._run(rows, yielded=self._on_row, generator=True)
        self._workers[-1].tag = "rows"
        worker.finished.connect(lambda: self._on_rows_finished() if run == self._rows_run else None)

    def _on_row(self, item) -> None:
        run, count, row = item
        if run != self._rows_run:
            return
        self.progress.setValue(count)
        if isinstance(row, str):
            self._skipped.append(row)
            return
        self.model.put(row)
        if row.id in self.workspace.selected_sources:
            self._select_rows(self.workspace.selected_sources)

    def _on_rows_finished(self) -> None:
        self.progress.hide()
        text = (f"{self.model.rowCount()} sources; select several (Ctrl/Shift-click) to compare "
                "them")
        clipped = sum(not row.light_in_gamut for row in self.model.rows())
        if clipped:
            text += (f"; {CLIPPED_MARK.strip()} after a headset light RGB: clipped, outside the "
                     f"headset's gamut ({clipped})")
        if self._skipped:
            text += f". Not shown ({len(self._skipped)}): " + "; ".join(self._skipped)
        self.status.setText(text)
        selected = self.table.selectionModel().selectedRows()
        if selected:
            self.table.scrollTo(selected[0], QAbstractItemView.ScrollHint.PositionAtCenter)
        self.rows_ready.emit()

    def _on_worker_finished(self) -> None:
        self._workers = [job for job in self._workers if job.running]

    def _on_worker_error(self, error) -> None:
        self.measure_button.setEnabled(True)
        self._show_error("The light source operation failed", describe_error(error))

    def _on_measured(self, measurement) -> None:
        self.measure_button.setEnabled(True)
        new_id = self._add_to_library(measurement.illuminant)
        self.status.setText(f"Measured {measurement.illuminant.name} with the "
                            f"{measurement.instrument}: Lv {measurement.Lv:.4g} cd/m², "
                            f"xy ({measurement.xy[0]:.4f}, {measurement.xy[1]:.4f}); "
                            f"saved as {new_id}")

    # -- library ------------------------------------------------------------------
    def _add_to_library(self, illuminant) -> str:
        new_id = self.library.add(illuminant)
        stored = self.library.get(new_id)
        profile = self.workspace.profile
        self.model.put(source_row(stored, profile.display_model(), k=profile.k))
        self.status.setText(f"Added {stored.name} to your library as {new_id} "
                            f"({self.library.root})")
        self.source_added.emit(new_id)
        return new_id

    def _show_error(self, title: str, text: str) -> None:
        self.last_error = text
        self.error_shown.emit(text)
        QMessageBox.critical(self, title, text)

    # -- selection, plot, swatches ---------------------------------------------------
    def _selected_ids(self) -> list[str]:
        rows = self.table.selectionModel().selectedRows()
        return [self.model.ids()[self.proxy.mapToSource(index).row()] for index in rows]

    def _apply_filter(self, text: str) -> None:
        # Filtering hides rows; it does not deselect sources: the rows it
        # removes leave the table's selection without touching the workspace's.
        self._syncing = True
        try:
            self.proxy.setFilterFixedString(text)
        finally:
            self._syncing = False
        self._select_rows(self.workspace.selected_sources)

    def _on_table_selection(self, *_):
        if self._syncing:
            return
        ids = self._selected_ids()
        if ids and tuple(ids) != self.workspace.selected_sources:
            self.workspace.set_selected_sources(ids)

    def _select_rows(self, ids) -> None:
        self._syncing = True
        try:
            selection = QItemSelection()
            for source_id in ids:
                if source_id in self.model.ids():
                    row = self.model.ids().index(source_id)
                    index = self.proxy.mapFromSource(self.model.index(row, 0))
                    if index.isValid():
                        selection.select(index, index)
            flags = (QItemSelectionModel.SelectionFlag.ClearAndSelect
                     | QItemSelectionModel.SelectionFlag.Rows)
            self.table.selectionModel().select(selection, flags)
        finally:
            self._syncing = False

    def _on_sources_changed(self) -> None:
        ids = self.workspace.selected_sources
        if tuple(self._selected_ids()) != tuple(ids):
            self._select_rows(ids)
        try:
            self._update_plot(ids)
            self._update_swatches(ids)
        except WorkbenchError as error:
            self._show_error("Cannot show the selected sources", describe_error(error))

    def _on_profile_changed(self) -> None:
        self._comparisons.clear()
        try:
            self._update_swatches(self.workspace.selected_sources)
        except WorkbenchError as error:
            self._show_error("Cannot show the selected sources", describe_error(error))
        self._start_rows()

    def _update_plot(self, ids) -> None:
        self.plot.show_sources([resolve_illuminant(i, self.library) for i in ids])

    def _update_swatches(self, ids) -> None:
        profile = self.workspace.profile
        display = profile.display_model()
        for source_id in ids:
            if source_id not in self._comparisons:
                illuminant = resolve_illuminant(source_id, self.library)
                self._comparisons[source_id] = (
                    colorchecker_comparison(illuminant, display, k=profile.k), illuminant.name)
        self.swatches.set_comparisons([self._comparisons[i][0] for i in ids],
                                      {i: self._comparisons[i][1] for i in ids})

    # -- dialogs --------------------------------------------------------------------
    def _ask_import(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Import a light source", "",
                                              "Spectra (*.csv *.xml);;All files (*)")
        if path:
            self.import_file(path)

    def _ask_export(self) -> None:
        ids = self._selected_ids() or list(self.workspace.selected_sources)
        path, _ = QFileDialog.getSaveFileName(self, f"Export {ids[0]}", f"{ids[0]}.csv",
                                              "CSV (*.csv);;IES TM-27 XML (*.xml)")
        if path:
            self.export_source(ids[0], path)

    def _ask_measure(self) -> None:
        from instruments.cs2000 import find_cs2000_ports

        try:
            ports = [(p, d) for p, d in find_cs2000_ports()]
        except Exception:  # noqa: BLE001 - no serial enumeration here: the emulator still works
            ports = []
        dialog = MeasureLightDialog(self.all_ids(), ports, self)
        dialog.booth_source.setCurrentText(self.workspace.selected_sources[0])
        if dialog.exec():
            self.measure_light(dialog.booth_source.currentData(), dialog.name.text(),
                               port=dialog.instrument.currentData(),
                               illuminance_lux=dialog.illuminance.value())

    def _metamer_of_selection(self) -> None:
        ids = self._selected_ids() or list(self.workspace.selected_sources)
        self.synthesize_metamer(ids[0])

    def showEvent(self, event):  # noqa: N802 - Qt's name
        super().showEvent(event)
        if not getattr(self, "_sized", False):
            self._sized = True
            width, height = self.width(), self.height()
            self.upper_splitter.setSizes([int(width * 0.6), int(width * 0.4)])
            swatches = min(self.swatches.sizeHint().height() + 24, height // 2)
            self.splitter.setSizes([height - swatches, swatches])

    # -- teardown -------------------------------------------------------------------
    def closeEvent(self, event):  # noqa: N802 - Qt's name
        self.shutdown()
        super().closeEvent(event)

    def shutdown(self, timeout_s: float = 10.0) -> None:
        """Stop the workers and wait for them; unsubscribe from the workspace."""
        for job in self._workers:
            job.quit()
        for job in self._workers:
            job.wait(timeout_s)
        for unsubscribe in self._unsubscribe:
            try:
                unsubscribe()
            except ValueError:
                pass
        self._unsubscribe = []
