"""Export: write the profile of the current diagnosis (validated before writing), and the runtime bundle
of the current profile (:func:`workbench.export.write_bundle`, off the GUI thread); show what was written."""

from __future__ import annotations

import json
from pathlib import Path

from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QFontDatabase
from PySide6.QtWidgets import (
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QPlainTextEdit,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gui.workers import CallWorker, describe_error

__all__ = ["ExportPage"]


class ExportPage(QWidget):
    """Choose where, write the profile, see the document that was written.

    Signals
    -------
    exported(object)
        The path of the profile written.
    bundle_written(object)
        The :class:`~workbench.export.bundle.BundleSummary` of the bundle written.
    """

    title = "Export"
    exported = Signal(object)
    bundle_written = Signal(object)

    def __init__(self, workspace, parent=None):
        super().__init__(parent)
        self.workspace = workspace
        self.explanation = QLabel("")
        self.explanation.setWordWrap(True)
        self.path = QLineEdit()
        self.path.setPlaceholderText("where to write the profile (*.vrprofile.json)")
        browse = QPushButton("…")
        browse.clicked.connect(self._choose)
        self.export_button = QPushButton("Write profile")
        self.export_button.setToolTip("validate the profile against the schema, then write it (Ctrl+E)")
        self.export_button.clicked.connect(lambda: self.export())
        self.status = QLabel("")
        self.status.setWordWrap(True)
        self.status.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.written = QPlainTextEdit(readOnly=True)
        self.written.setFont(QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont))
        row = QHBoxLayout()
        row.addWidget(QLabel("profile"))
        row.addWidget(self.path, 1)
        row.addWidget(browse)
        row.addWidget(self.export_button)
        self.bundle_path = QLineEdit()
        self.bundle_path.setPlaceholderText("folder of the runtime bundle (new, empty, or an earlier bundle)")
        self.bundle_button = QPushButton("Write runtime bundle")
        self.bundle_button.setToolTip("the current profile's 3D LUT, display inverse, lights table and the "
                                      "runtime loaders, as 'export PROFILE --bundle DIR' writes them")
        self.bundle_button.clicked.connect(lambda: self.write_bundle())
        self.bundle_status = QLabel("")
        self.bundle_status.setWordWrap(True)
        self.bundle_status.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        bundle_row = QHBoxLayout()
        bundle_row.addWidget(QLabel("bundle"))
        bundle_row.addWidget(self.bundle_path, 1)
        bundle_row.addWidget(self.bundle_button)
        self._workers: list = []
        layout = QVBoxLayout(self)
        layout.addWidget(self.explanation)
        layout.addLayout(row)
        layout.addWidget(self.status)
        layout.addLayout(bundle_row)
        layout.addWidget(self.bundle_status)
        layout.addWidget(self.written, 1)
        workspace.subscribe("diagnosis-changed", lambda ws: self._refresh())
        workspace.subscribe("profile-changed", lambda ws: self._refresh_bundle())
        self._refresh()
        self._refresh_bundle()

    def _refresh_bundle(self) -> None:
        path = self.workspace.profile_path
        if path is not None and not self.bundle_path.text():
            self.bundle_path.setText(str(path.parent / f"{path.name.split('.')[0]}-bundle"))

    def _refresh(self) -> None:
        diagnosis = self.workspace.diagnosis
        self.export_button.setEnabled(diagnosis is not None)
        if diagnosis is None:
            self.explanation.setText("<i>Nothing to export yet: calibrate, or open a session (File ▸ Open).</i>")
            return
        document = diagnosis.to_json()
        self.explanation.setText(
            f"Writes the <b>{document['extended']['model']}</b> model of "
            f"<code>{document['session']['source']}</code> with its held-out validation figures, the findings "
            "and the paper's lights, as <code>diagnose SESSION --export PROFILE</code> does. The document is "
            "validated against <code>profiles/vrprofile.schema.json</code> before it is written, and read back "
            "after.")
        if not self.path.text():
            source = Path(document["session"]["source"])
            folder = source if source.is_dir() else source.parent
            stem = folder.name if source.is_dir() or source.name == "session.csv" else source.stem
            self.path.setText(str(folder / f"{stem}.vrprofile.json"))

    def _choose(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Write profile", self.path.text(), "Profile (*.vrprofile.json)")
        if path:
            self.path.setText(path)

    def export(self, path=None) -> Path | None:
        """Write the profile to ``path`` (default: the one in the field); show it; None on error."""
        path = Path(path or self.path.text().strip())
        try:
            written = self.workspace.export_profile(path)
        except (WorkbenchError, OSError) as error:
            self.status.setText(f"<span style='color:#b03a2e'><b>not written:</b> {describe_error(error)}</span>")
            return None
        text = written.read_text(encoding="utf-8")
        document = json.loads(text)
        validation = document.get("validation") or {}
        figures = ", ".join(f"{k} {v:.3g}" for k, v in validation.items() if isinstance(v, float))
        self.status.setText(f"<b>wrote</b> <code>{written}</code> ({len(text)} bytes; model "
                            f"{document['display_model']['type']}; {len(document.get('lights', []))} lights; "
                            f"held-out {figures}); it is now the current profile")
        self.written.setPlainText(text)
        self.exported.emit(written)
        return written

    def write_bundle(self, directory=None) -> None:
        """Write the runtime bundle of the current profile into ``directory`` (off the GUI thread)."""
        from workbench.export import write_bundle

        text = str(directory or self.bundle_path.text()).strip()
        if not text:
            self.bundle_status.setText("<span style='color:#b03a2e'>choose a folder for the bundle</span>")
            return
        profile, target = self.workspace.profile, Path(text)
        self.bundle_button.setEnabled(False)
        self.bundle_status.setText(f"writing {target}…")
        worker = CallWorker(lambda: write_bundle(profile, target), self)
        worker.done.connect(self._bundle_done)
        worker.failed.connect(lambda message: self.bundle_status.setText(
            f"<span style='color:#b03a2e'><b>bundle not written:</b> {message}</span>"))
        worker.finished.connect(lambda: (self.bundle_button.setEnabled(True), self._workers.remove(worker)))
        self._workers.append(worker)
        worker.start()

    def _bundle_done(self, summary) -> None:
        accuracy = summary.cube_accuracy
        files = sorted(p.relative_to(summary.directory).as_posix() for p in Path(summary.directory).rglob("*")
                       if p.is_file())
        self.bundle_status.setText(
            f"<b>wrote</b> <code>{summary.directory}</code>: {len(summary.lights)} light(s), "
            f"display_inverse.cube {accuracy.size}³ (ΔE00 vs the exact inverse: mean {accuracy.mean_dE00:.3f}, "
            f"max {accuracy.max_dE00:.3f}); {len(files)} files: {', '.join(files[:12])}"
            + (", …" if len(files) > 12 else ""))
        self.bundle_written.emit(summary)

    def shutdown(self) -> None:
        """Wait for a bundle being written (teardown)."""
        for worker in list(self._workers):
            worker.wait()
