"""Scene page: the virtual lightbooth at level 1 and level 2 side by side, with the per-patch error table.

One pyvistaqt ``QtInteractor`` holds two renderers (level 1 left, level 2
right, cameras linked) built once by :func:`workbench.scene.booth.build_booth`;
switching the source or the profile computes the new images
(:func:`workbench.scene.level_images`, a few ms) and writes them into the
existing textures (:func:`workbench.scene.booth.relight_booth`). Anti-aliasing
is off on purpose: on Mesa llvmpipe 8× MSAA costs 50–90 ms a frame, and the
flat textured patches gain nothing from it.

"Show in headset browser" serves the same lightbooth to a headset's browser
(the WebXR page of :mod:`workbench.vr`, through the window's one server,
:class:`~workbench.gui.headset_browser.HeadsetBrowser`, which the Calibrate
page shares): it makes the runtime bundle of the current profile with the
page's sources in a worker (a few seconds; a busy bar meanwhile), serves it,
and shows the URL, a QR code and the page's state. The page's source is pushed
to the headset as it changes, and a source switched in the headset is shown
here; the headset's level (1 or 2, both shown here side by side) is named.
The button again stops the server.
"""

from __future__ import annotations

import threading

import numpy as np
from PySide6.QtCore import QPoint, Qt, QTimer, Signal
from PySide6.QtGui import QColor, QImage, QPainter
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QProgressBar,
    QPushButton,
    QSizePolicy,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gui.widgets.headset_panel import HeadsetPanel
from workbench.illuminants.user_library import resolve_illuminant
from workbench.scene import LEVELS, level_images, patch_errors, scene_content

__all__ = ["ScenePage"]

_ROWS = ("Level 2 shows", "Level 1 ΔE00", "Level 2 ΔE00", "L1 |ΔR ΔG ΔB|", "L2 |ΔR ΔG ΔB|",
         "DAC_t (R G B)")
"""Rows of the error table; its columns are the 24 patches."""

WARM_UP_DELAY_MS = 1500
"""How long after the page is made the surfaces thread starts (after the window's first paint)."""


def _warm_up() -> None:
    """Prepare the booth's surfaces (numpy only: no VTK object, no widget)."""
    scene_content()


_VIEW_TITLES = {1: "Level 1: authored textures, light colour set",
                2: "Level 2: textures re-authored for the source"}


def _triplet(values) -> str:
    return " ".join(f"{int(v):d}" for v in values)


class ScenePage(QWidget):
    """The lightbooth at both levels under one source, and the paper's Table 4 per patch."""

    title = "Scene"

    source_changed = Signal(str)
    """Emitted after both views show a new source (its id)."""

    def __init__(self, workspace, parent=None):
        super().__init__(parent)
        self.workspace = workspace
        self._source_id = workspace.selected_sources[0]
        self._images: dict[int, object] = {}
        self._errors = None
        self.headset_browser = None
        self._bundler = None
        self._bundle_profile = None
        self._headset_scene = None  # the scene of the server's last status (a change there is the headset's)

        self.source_box = QComboBox()
        self.source_box.setToolTip("The light source both views are lit by")
        self.source_box.setMinimumContentsLength(18)
        self.caption = QLabel()
        self.caption.setWordWrap(True)

        # The 3D view is made when the page is first shown: VTK, pyvista and
        # the plate (~1.5 s together) stay out of the window's start-up. A
        # plain thread prepares the booth's surfaces (the plate: numpy, no VTK
        # object, no widget) once the window has painted; the first show
        # joins it, imports VTK (in the GUI thread: a VTK module's import
        # holds the GIL for long stretches, which would stall a calibration
        # running meanwhile) and builds the meshes.
        self.plotter = None
        self._building = False
        self._placeholder = QLabel("Preparing the lightbooth …")
        self._placeholder.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self._placeholder.setMinimumSize(640, 320)
        self._handles = {}
        self._warmup = threading.Thread(target=_warm_up, name="scene-warm-up", daemon=True)
        QTimer.singleShot(WARM_UP_DELAY_MS, self._start_warm_up)

        self.table = QTableWidget(len(_ROWS), 24)
        self.table.setVerticalHeaderLabels(_ROWS)
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSortingEnabled(False)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Stretch)
        self.table.horizontalHeader().setMinimumSectionSize(44)
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        font = self.table.font()
        font.setPointSizeF(font.pointSizeF() * 0.9)
        self.table.setFont(font)
        self.summary = QLabel()
        self.summary.setWordWrap(True)
        self.summary.setTextFormat(Qt.TextFormat.RichText)

        self.headset_button = QPushButton("Show in headset browser")
        self.headset_button.setCheckable(True)
        self.headset_button.setToolTip("serve this lightbooth (the current profile, these sources) to a "
                                       "headset's browser as a WebXR page; again: stop serving")
        self.headset_button.setEnabled(False)  # until the window gives its server
        self.headset_button.clicked.connect(self._toggle_headset)
        self.headset_busy = QProgressBar()
        self.headset_busy.setRange(0, 0)  # busy: write_bundle says nothing as it goes
        self.headset_busy.setFormat("making the headset's bundle…")
        self.headset_busy.setTextVisible(True)
        self.headset_busy.setMaximumWidth(260)
        self.headset_busy.setVisible(False)
        self.headset = HeadsetPanel(inline_qr=False, idle_text=(
            "not served to a headset's browser: “Show in headset browser” serves this lightbooth as a WebXR page"))
        top = QHBoxLayout()
        top.addWidget(QLabel("Light source:"))
        top.addWidget(self.source_box)
        top.addWidget(self.caption, 1)
        top.addWidget(self.headset_button)
        # The row keeps its height whatever it shows: the 3D views are not resized under VTK's feet.
        self._headset_row = QWidget()
        headset_row = QHBoxLayout(self._headset_row)
        headset_row.setContentsMargins(0, 0, 0, 0)
        headset_row.addWidget(self.headset_busy)
        headset_row.addWidget(self.headset, 1)
        self._headset_row.setFixedHeight(max(self.headset_busy.sizeHint().height(),
                                             self.headset.sizeHint().height(),
                                             QPushButton("QR code").sizeHint().height()))
        bottom = QWidget()
        bottom_layout = QVBoxLayout(bottom)
        bottom_layout.setContentsMargins(0, 0, 0, 0)
        table_title = QLabel("<b>Per-patch errors on the ColorChecker</b> (the paper's Table 4, "
                             "patch by patch; columns are patches 1–24, hover for the name): "
                             "engine DAC vs the theoretical DAC_t in counts, and CIEDE2000 of what "
                             "the headset shows vs the colour under the source")
        table_title.setWordWrap(True)
        bottom_layout.addWidget(table_title)
        bottom_layout.addWidget(self.table, 1)
        bottom_layout.addWidget(self.summary)
        bottom.setSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Maximum)
        self._bottom = bottom
        self._layout = layout = QVBoxLayout(self)
        layout.addLayout(top)
        layout.addWidget(self._headset_row)
        layout.addWidget(self._placeholder, 1)  # the views take every pixel the table leaves
        layout.addWidget(bottom, 0)

        self._refill_sources()
        self._update_caption()
        self.source_box.currentIndexChanged.connect(self._on_box)
        self._unsubscribe = [
            workspace.subscribe("sources-changed", lambda ws: self._refill_sources()),
            workspace.subscribe("profile-changed", lambda ws: self._relight_if_built()),
            workspace.subscribe("profile-changed", lambda ws: self._headset_note()),
        ]
        self.source_changed.connect(self._push_scene)

    def _start_warm_up(self) -> None:
        if not getattr(self, "_shut", False) and not self._warmup.is_alive() and not self._handles:
            self._warmup.start()

    def _ensure_built(self) -> None:
        """Make the interactor and build both booths (once), lit by the current source and profile."""
        if self._handles or self._building or getattr(self, "_shut", False):
            return
        self._building = True  # creating the native VTK window can send events back here
        try:
            self._build()
        except WorkbenchError as error:  # e.g. a user-library spectrum that no longer reads
            self._cannot_show(error)
        finally:
            self._building = False

    def _build(self) -> None:
        if self._warmup.is_alive():
            self._warmup.join()
        # The images first: a source that cannot be read leaves nothing half built.
        profile = self.workspace.profile
        display = profile.display_model()
        illuminant = resolve_illuminant(self._source_id)
        images = {level: level_images(illuminant, display, level, k=profile.k) for level in LEVELS}
        from pyvistaqt import QtInteractor

        from workbench.scene.booth import build_booth

        # multi_samples=1 and no FXAA: anti-aliasing off on purpose (module doc).
        plotter = QtInteractor(self, shape=(1, 2), multi_samples=1, auto_update=False,
                               border=False)
        plotter.disable_anti_aliasing(all_renderers=True)
        plotter.setMinimumSize(640, 320)
        self._layout.replaceWidget(self._placeholder, plotter)
        self.plotter = plotter
        self._placeholder.hide()
        self._placeholder.deleteLater()
        for column, level in enumerate(LEVELS):
            self.plotter.subplot(0, column)
            self._images[level] = images[level]
            self._handles[level] = build_booth(self.plotter, self._images[level])
            self.plotter.add_text(_VIEW_TITLES[level], position="upper_left", font_size=10,
                                  color="white")
        self.plotter.link_views()
        self.plotter.show()
        self._fit_cameras()
        self._update_errors(illuminant)

    def _relight_if_built(self) -> None:
        if self._handles:
            self._relight()
        else:
            self._update_caption()

    # -- public ---------------------------------------------------------------
    @property
    def source_id(self) -> str:
        """The source both views show."""
        return self._source_id

    def select_source(self, source_id: str) -> None:
        """Re-light both views with ``source_id``; returns after both have rendered."""
        source_id = str(source_id)
        if self.source_box.findData(source_id) < 0:
            self.source_box.blockSignals(True)
            self.source_box.addItem(source_id, source_id)
            self.source_box.blockSignals(False)
        self._source_id = source_id
        self.source_box.blockSignals(True)
        self.source_box.setCurrentIndex(self.source_box.findData(source_id))
        self.source_box.blockSignals(False)
        if self._handles:
            self._relight()
        else:
            self._ensure_built()
            if self._handles:
                self.plotter.ren_win.Render()
                self._update_caption()
            self.source_changed.emit(self._source_id)

    def level_images(self, level: int):
        """The :class:`workbench.scene.LevelImages` the view at ``level`` shows now."""
        self._ensure_built()
        return self._images[level]

    def rendered_image(self) -> np.ndarray:
        """The render window as an (H, W, 3) uint8 array, rows top first (VTK's own read-back)."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

        self._ensure_built()
        window = self.plotter.ren_win
        window.Render()
        grab = vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()  # the back buffer just rendered, not what a compositor kept
        grab.Update()
        output = grab.GetOutput()
        width, height, _ = output.GetDimensions()
        pixels = vtk_to_numpy(output.GetPointData().GetScalars()).reshape(height, width, -1)
        return np.ascontiguousarray(pixels[::-1, :, :3])

    def patch_screen_point(self, level: int, index: int) -> tuple[int, int]:
        """(column, row) in :meth:`rendered_image` of ColorChecker patch ``index``'s centre at ``level``."""
        self._ensure_built()
        from workbench.scene.booth import board_patch_world_point

        renderer = self.plotter.renderers[LEVELS.index(level)]
        renderer.SetWorldPoint(*board_patch_world_point(self._handles[level], index), 1.0)
        renderer.WorldToDisplay()
        x, y, _ = renderer.GetDisplayPoint()
        height = self.plotter.ren_win.GetSize()[1]
        return int(round(x)), height - 1 - int(round(y))

    def save_screenshot(self, path) -> None:
        """Write the whole page as PNG, the 3D views from VTK's own read-back."""
        self._ensure_built()
        self.plotter.ren_win.Render()
        pixmap = self.grab()
        render = np.ascontiguousarray(self.rendered_image())
        height, width, _ = render.shape
        image = QImage(render.data, width, height, 3 * width, QImage.Format.Format_RGB888).copy()
        painter = QPainter(pixmap)
        target = self.plotter.mapTo(self, QPoint(0, 0))
        painter.drawImage(target, image.scaled(self.plotter.size()))
        painter.end()
        if not pixmap.save(str(path)):
            raise OSError(f"could not write {path}")

    # -- the headset's browser --------------------------------------------------
    def use_headset_browser(self, service) -> None:
        """Serve the lightbooth through ``service`` (the window's :class:`~workbench.gui.headset_browser.HeadsetBrowser`)."""
        if self.headset_browser is service:
            return
        self.headset_browser = service
        self.headset.bind(service)
        service.status_changed.connect(self._headset_status)
        self.headset_button.setEnabled(True)
        self._headset_status(service.status())

    @property
    def serving_scene(self) -> bool:
        """Whether the headset's browser is served this lightbooth (a server with a bundle runs)."""
        service = self.headset_browser
        return service is not None and service.bundle_folder is not None

    def show_in_headset(self) -> None:
        """Make the bundle of the current profile and sources (in a worker), then serve it; the panel
        shows the URL, the QR code and the page's state once it is served."""
        service = self.headset_browser
        if service is None or self._bundler is not None:
            return
        from workbench.gui.headset_browser import make_scene_bundle
        from workbench.gui.workers import CallWorker

        profile = self.workspace.profile
        sources = list(self.workspace.selected_sources)
        if self._source_id not in sources:
            sources.append(self._source_id)
        folder = service.scratch_folder() / "bundle"
        self._bundle_profile = profile
        self._bundler = CallWorker(lambda: make_scene_bundle(profile, sources, folder), self)
        self._bundler.done.connect(self._bundle_made)
        self._bundler.failed.connect(self._bundle_failed)
        self._bundler.finished.connect(self._bundler_finished)
        self.headset_busy.setVisible(True)
        self.headset.setVisible(False)
        self.headset_button.setEnabled(False)
        self._bundler.start()

    def _bundler_finished(self) -> None:
        self._bundler = None
        self.headset_busy.setVisible(False)
        self.headset.setVisible(True)
        self.headset_button.setEnabled(self.headset_browser is not None)
        self._headset_status(self.headset_browser.status() if self.headset_browser else None)

    def _bundle_made(self, made) -> None:
        service = self.headset_browser
        from workbench.gui.calibration_setup import WEBXR_DEFAULT_ADDRESS

        server = service.server
        host, port = (server.host, server.port) if server is not None else WEBXR_DEFAULT_ADDRESS
        restarted = server is not None and server.page.connected  # that page must reload for the lightbooth
        try:
            service.start(host, port, bundle=made.folder, source=self._source_id)
        except WorkbenchError as error:
            self.headset.setVisible(True)
            self.headset.show_problem(str(error))
            return
        notes = []
        if restarted:
            notes.append("reload the page in the headset to load the lightbooth")
        if made.left_out:
            notes.append(f"{', '.join(made.left_out)} cannot go into a bundle (your own spectra)")
        self._headset_note(notes)

    def _bundle_failed(self, message: str) -> None:
        self.headset.setVisible(True)
        self.headset.show_problem(f"the headset's bundle could not be made: {message}")

    def _toggle_headset(self) -> None:
        service = self.headset_browser
        if service is None:
            return
        if self.serving_scene:
            if service.in_use:
                self.headset.show_problem(service.IN_USE_MESSAGE)
                self.headset_button.setChecked(True)
                return
            service.stop()
        else:
            if service.in_use:
                self.headset.setVisible(True)
                self.headset.show_problem("a calibration is showing its patches on the page: the lightbooth "
                                          "can be served when it has ended")
                self.headset_button.setChecked(False)
                return
            self.show_in_headset()

    def _headset_status(self, status) -> None:
        """Follow the server: the button's state, and a source switched in the headset."""
        serving = status is not None and self.serving_scene
        previous, self._headset_scene = self._headset_scene, (dict(status.scene) if serving else None)
        self.headset_button.blockSignals(True)
        self.headset_button.setChecked(serving or self._bundler is not None)
        self.headset_button.blockSignals(False)
        self.headset.setVisible(self._bundler is None)
        if not serving:
            if status is not None:
                self.headset.set_note("served for the calibration, without the lightbooth")
            return
        source = status.scene.get("source")
        if source and source != self._source_id and previous is not None and status.scene != previous:
            # switched in the headset (a scene the page has not pushed, e.g. a new server's first, is not)
            if self._handles:
                self.select_source(source)
            else:
                self._source_id = source
                self._refill_sources()
                self._update_caption()
        self._headset_note()

    def _headset_note(self, extra=None) -> None:
        if not self.serving_scene:
            return
        status = self.headset_browser.status()
        scene = status.scene if status is not None else {}
        notes = [f"the headset shows {scene.get('source')} at level {scene.get('level')}"]
        if self._bundle_profile is not None and self._bundle_profile is not self.workspace.profile:
            notes.append("the profile has changed since: press the button twice to serve the new one")
        self._extra_notes = list(extra) if extra is not None else getattr(self, "_extra_notes", [])
        self.headset.set_note("; ".join(notes + self._extra_notes))

    def _push_scene(self, source_id: str) -> None:
        service = self.headset_browser
        if service is not None and self.serving_scene and not service.set_scene(source_id):
            self._headset_note([f"{source_id} is not in the headset's bundle (press the button twice to "
                                "make a new one)"])

    # -- internals ------------------------------------------------------------
    def _refill_sources(self) -> None:
        ids = list(self.workspace.selected_sources)
        if self._source_id not in ids:
            ids.append(self._source_id)
        self.source_box.blockSignals(True)
        self.source_box.clear()
        for source_id in ids:
            self.source_box.addItem(source_id, source_id)
        self.source_box.setCurrentIndex(self.source_box.findData(self._source_id))
        self.source_box.blockSignals(False)

    def _on_box(self, index: int) -> None:
        source_id = self.source_box.itemData(index)
        if source_id and source_id != self._source_id:
            self.select_source(source_id)

    def _relight(self) -> None:
        if getattr(self, "_shut", False):
            return
        try:
            self._relight_now()
        except WorkbenchError as error:  # e.g. a user-library spectrum that no longer reads
            self._cannot_show(error)
            self.source_changed.emit(self._source_id)

    def _relight_now(self) -> None:
        from workbench.scene.booth import relight_booth

        profile = self.workspace.profile
        display = profile.display_model()
        illuminant = resolve_illuminant(self._source_id)
        for level in LEVELS:
            self._images[level] = level_images(illuminant, display, level, k=profile.k)
            relight_booth(self._handles[level], self._images[level])
        self.plotter.ren_win.Render()  # synchronous: both renderers of the one window
        self._update_errors(illuminant)
        self._update_caption(illuminant)
        self.source_changed.emit(self._source_id)

    def _cannot_show(self, error: WorkbenchError) -> None:
        self.caption.setText(f"Cannot show {self._source_id}: {error}")

    def _update_caption(self, illuminant=None) -> None:
        try:
            illuminant = illuminant or resolve_illuminant(self._source_id)
        except WorkbenchError as error:
            self._cannot_show(error)
            return
        profile = self.workspace.profile
        device = profile.device.get("name") or profile.device.get("model") or "headset"
        self.caption.setText(f"{illuminant.name} on {device}: left the level-1 textures, right "
                             "level 2, as the headset shows them (on this sRGB monitor)")

    def _update_errors(self, illuminant=None) -> None:
        illuminant = illuminant or resolve_illuminant(self._source_id)
        profile = self.workspace.profile
        errors = patch_errors(illuminant, profile.display_model(), k=profile.k)
        self._errors = errors
        level1, level2 = errors.level(1), errors.level(2)
        for column, (a, b) in enumerate(zip(level1, level2)):
            swatch = self._images[2].patch_rgb8[column]
            header = QTableWidgetItem(str(a.patch))
            header.setToolTip(a.name)
            self.table.setHorizontalHeaderItem(column, header)
            cells = ("", f"{a.dE00:.1f}", f"{b.dE00:.1f}", _triplet(a.abs_dac), _triplet(b.abs_dac),
                     _triplet(a.target_dac))
            for row, text in enumerate(cells):
                item = QTableWidgetItem(text)
                item.setTextAlignment(Qt.AlignmentFlag.AlignCenter)
                item.setToolTip(f"patch {a.patch}: {a.name}")
                if row == 0:
                    item.setBackground(QColor(*(int(v) for v in swatch)))
                self.table.setItem(row, column, item)
        lines = []
        for level in LEVELS:
            s = errors.summary[level]
            mean = ", ".join(f"{v:.1f}" for v in s.mean_abs)
            sd = ", ".join(f"{v:.1f}" for v in s.sd)
            text = (f"<b>Level {level}</b>: mean |ΔR, ΔG, ΔB| = {mean} (sd {sd}) counts; "
                    f"ΔE00 mean {s.mean_dE00:.2f}, max {s.max_dE00:.2f}")
            if level in errors.paper:
                paper_mean, paper_sd = errors.paper[level]
                text += (f"; paper (ideal sRGB pipeline): {', '.join(f'{v:g}' for v in paper_mean)}"
                         f" (sd {', '.join(f'{v:g}' for v in paper_sd)})")
            lines.append(text)
        lines.append(f"Display model: {errors.display}")
        self.summary.setText("<br>".join(lines))
        self.table.resizeRowsToContents()
        height = (self.table.horizontalHeader().height() + 2 * self.table.frameWidth()
                  + sum(self.table.rowHeight(r) for r in range(self.table.rowCount())))
        self.table.setFixedHeight(height + 2)

    def error_summary(self):
        """The current :class:`workbench.scene.SourceErrors`."""
        self._ensure_built()
        return self._errors

    def _fit_cameras(self) -> None:
        from workbench.scene.booth import booth_camera

        if self.plotter is None:
            return
        width, height = self.plotter.ren_win.GetSize()
        if width <= 0 or height <= 0:
            return
        self.plotter.subplot(0, 0)
        booth_camera(self.plotter, aspect=(width / len(LEVELS)) / height)

    def resizeEvent(self, event):  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._fit_cameras()

    def showEvent(self, event):  # noqa: N802 - Qt's name
        super().showEvent(event)
        if self._handles:
            self._fit_cameras()
        else:  # build after the show has been handled, not inside it
            QTimer.singleShot(0, self._ensure_built)

    def closeEvent(self, event):  # noqa: N802 - Qt's name
        self.shutdown()
        super().closeEvent(event)

    def shutdown(self) -> None:
        """Unsubscribe and close the interactor (``plotter.close()``); idempotent.

        The main window calls it at teardown: a page inside a stacked widget
        gets no ``closeEvent`` of its own, and an interactor left open crashes
        the process at exit.
        """
        for unsubscribe in getattr(self, "_unsubscribe", []):
            try:
                unsubscribe()
            except ValueError:
                pass
        self._unsubscribe = []
        self._shut = True
        if self._bundler is not None:
            self._bundler.wait()
        if self._warmup.is_alive():
            self._warmup.join(timeout=60)
        if self.plotter is not None and not getattr(self.plotter, "_closed", True):
            self.plotter.close()
