"""Export: write the profile of the current diagnosis (validated before writing), and the runtime bundle
of the current profile (:func:`workbench.export.write_bundle`, off the GUI thread); show what was written.

The page shows a summary first (:func:`export_summary_html`): the files written, the display model and
the candidate the model choice exported, the held-out validation figures (mean, p95, max ΔE00), the
lights and the bundle; "Show the JSON" shows the document as written, in its place.
"""

from __future__ import annotations

import html
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
    QStackedWidget,
    QTextBrowser,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from workbench.errors import WorkbenchError
from workbench.gui.workers import CallWorker, describe_error

__all__ = ["ExportPage", "export_summary_html"]

_RED = "#b03a2e"


def _code(text) -> str:
    return f"<code>{html.escape(str(text))}</code>"


def _number(value, digits: int = 2) -> str:
    return f"{value:.{digits}f}" if isinstance(value, (int, float)) and not isinstance(value, bool) else "—"


def export_summary_html(document: dict | None, path=None, size: int | None = None, model_choice: dict | None = None,
                        bundle=None, bundle_files: tuple = ()) -> str:
    """What the Export page says was written, as HTML.

    ``document``: the profile as written (read back), or None before anything was written;
    ``path``, ``size``: where and how many bytes; ``model_choice``: the diagnosis's
    ``to_json()["model_choice"]`` (the exported candidate), where there is a diagnosis; ``bundle``: the
    :class:`~workbench.export.bundle.BundleSummary` of the bundle written, with its ``bundle_files``.
    """
    parts = []
    if document is None:
        parts.append("<p><i>No profile written yet: <b>Write profile</b> (Ctrl+E) validates it against the "
                     "schema, writes it and reads it back; this page then sums up what was written.</i></p>")
    else:
        parts.append("<h3>Written</h3><table cellspacing='0' cellpadding='3'>"
                     f"<tr><td><b>profile</b></td><td>{_code(path)} ({size} bytes), validated against "
                     "<code>profiles/vrprofile.schema.json</code> before it was written and read back after; "
                     "it is now the current profile</td></tr>")
        if bundle is not None:
            accuracy = bundle.cube_accuracy
            names = ", ".join(bundle_files[:12]) + (", …" if len(bundle_files) > 12 else "")
            parts.append(f"<tr><td><b>runtime bundle</b></td><td>{_code(bundle.directory)}: {len(bundle_files)} "
                         f"files ({html.escape(names)}); display_inverse.cube {accuracy.size}³, ΔE00 against the "
                         f"exact inverse mean {accuracy.mean_dE00:.3f}, max {accuracy.max_dE00:.3f}</td></tr>")
        else:
            parts.append("<tr><td><b>runtime bundle</b></td><td><i>not written (Write runtime bundle)</i></td></tr>")
        parts.append("</table>")
        model = document.get("display_model") or {}
        components = (model.get("parameters") or {}).get("components")
        line = f"<b>{html.escape(str(model.get('type', '?')))}</b>"
        if components:
            line += f" ({html.escape(', '.join(map(str, components)))})"
        parts.append(f"<h3>Display model</h3><p>{line}")
        chosen = (model_choice or {}).get("chosen")
        if chosen:
            scores = (model_choice or {}).get("cv_mean_dE00") or {}
            score = scores.get(chosen)
            parts.append(f"<br>exported candidate: <b>{html.escape(str(chosen))}</b>"
                         + (f", cross-validated mean ΔE00 {score:.3f} on the fit rows, the best of {len(scores)}"
                            if isinstance(score, (int, float)) else ""))
        parts.append("</p>")
        validation = document.get("validation") or {}
        figures = "".join(f"<td align='center'>&nbsp;{label}<br><span style='font-size:x-large'><b>"
                          f"{_number(validation.get(key))}</b></span>&nbsp;</td>"
                          for key, label in (("mean_dE00", "mean ΔE00"), ("p95_dE00", "p95 ΔE00"),
                                             ("max_dE00", "max ΔE00")))
        count = validation.get("n")
        protocol = validation.get("protocol")
        parts.append("<h3>Validation on held-out colours</h3>"
                     f"<table cellspacing='0' cellpadding='4'><tr>{figures}</tr></table>"
                     f"<p>{count if count is not None else '?'} colours"
                     + (f"; protocol: {html.escape(str(protocol))}" if protocol else "") + "</p>")
        lights = document.get("lights") or []
        names = ", ".join(html.escape(str(light.get("name") or light.get("id") or "?")) for light in lights)
        parts.append(f"<h3>Lights</h3><p>{len(lights)} light{'s' if len(lights) != 1 else ''}"
                     + (f": {names}" if names else "") + "</p>")
    return "".join(parts)


class ExportPage(QWidget):
    """Choose where, write the profile, see the document that was written.

    Attributes
    ----------
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
        browse = QToolButton(text="…", toolTip="choose where to write the profile")
        browse.clicked.connect(self._choose)
        self.export_button = QPushButton("Write profile")
        self.export_button.setToolTip("validate the profile against the schema, then write it (Ctrl+E)")
        self.export_button.clicked.connect(lambda: self.export())
        self.status = QLabel("")
        self.status.setWordWrap(True)
        self.status.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.written = QPlainTextEdit(readOnly=True)
        self.written.setFont(QFontDatabase.systemFont(QFontDatabase.SystemFont.FixedFont))
        self.summary = QTextBrowser()
        self.summary.setOpenLinks(False)
        # The summary first; the raw document one click away, in its place.
        self.view = QStackedWidget()
        self.view.addWidget(self.summary)
        self.view.addWidget(self.written)
        self.json_button = QPushButton("Show the JSON")
        self.json_button.setCheckable(True)
        self.json_button.setToolTip("the profile document as written (click again for the summary)")
        self.json_button.toggled.connect(self.show_json)
        self.json_button.setText("Show the summary")  # as wide as its wider text: it does not jump
        self.json_button.setMinimumWidth(self.json_button.sizeHint().width())
        self.json_button.setText("Show the JSON")
        self._written: tuple | None = None  # (path, bytes, document) of the profile written
        self._bundle = None  # (BundleSummary, its files)
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
        view_row = QHBoxLayout()
        view_row.addStretch(1)
        view_row.addWidget(self.json_button)
        layout.addLayout(view_row)
        layout.addWidget(self.view, 1)
        workspace.subscribe("diagnosis-changed", lambda ws: self._refresh())
        workspace.subscribe("profile-changed", lambda ws: self._refresh_bundle())
        self._refresh()
        self._refresh_bundle()

    def _refresh_bundle(self) -> None:
        if self._bundle is not None:  # another profile is current: the bundle written was of the last one
            self._bundle = None
            self._show_summary()
        path = self.workspace.profile_path
        if path is not None and not self.bundle_path.text():
            self.bundle_path.setText(str(path.parent / f"{path.name.split('.')[0]}-bundle"))

    def show_json(self, shown: bool = True) -> None:
        """Show the document as written (``shown``) or the summary."""
        if self.json_button.isChecked() != shown:
            self.json_button.setChecked(shown)  # comes back here through toggled
            return
        self.view.setCurrentIndex(int(shown))
        self.json_button.setText("Show the summary" if shown else "Show the JSON")

    def _show_summary(self) -> None:
        diagnosis = self.workspace.diagnosis
        choice = None if diagnosis is None else diagnosis.to_json().get("model_choice")
        path, size, document = self._written or (None, None, None)
        bundle, files = self._bundle or (None, ())
        self.summary.setHtml(export_summary_html(document, path, size, choice, bundle, files))

    def _refresh(self) -> None:
        diagnosis = self.workspace.diagnosis
        self.export_button.setEnabled(diagnosis is not None)
        self._written = None  # a new diagnosis: its profile is not written yet
        self.written.setPlainText("")
        self._show_summary()
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
            self.status.setText(f"<span style='color:{_RED}'><b>not written:</b> {describe_error(error)}</span>")
            return None
        text = written.read_text(encoding="utf-8")
        document = json.loads(text)
        validation = document.get("validation") or {}
        self.status.setText(f"<b>wrote</b> {_code(written)} (held-out mean ΔE00 "
                            f"{_number(validation.get('mean_dE00'))}); it is now the current profile")
        self.written.setPlainText(text)
        self._written = (written, len(text.encode("utf-8")), document)
        self._show_summary()
        self.show_json(False)
        self.exported.emit(written)
        return written

    def write_bundle(self, directory=None) -> None:
        """Write the runtime bundle of the current profile into ``directory`` (off the GUI thread)."""
        from workbench.export import write_bundle

        text = str(directory or self.bundle_path.text()).strip()
        if not text:
            self.bundle_status.setText(f"<span style='color:{_RED}'>choose a folder for the bundle</span>")
            return
        profile, target = self.workspace.profile, Path(text)
        self.bundle_button.setEnabled(False)
        self.bundle_status.setText(f"writing {target}…")
        worker = CallWorker(lambda: write_bundle(profile, target), self)
        worker.done.connect(self._bundle_done)
        worker.failed.connect(lambda message: self.bundle_status.setText(
            f"<span style='color:{_RED}'><b>bundle not written:</b> {message}</span>"))
        worker.finished.connect(lambda: (self.bundle_button.setEnabled(True), self._workers.remove(worker)))
        self._workers.append(worker)
        worker.start()

    def _bundle_done(self, summary) -> None:
        files = tuple(sorted(p.relative_to(summary.directory).as_posix()
                             for p in Path(summary.directory).rglob("*") if p.is_file()))
        self.bundle_status.setText(f"<b>wrote</b> {_code(summary.directory)}: {len(summary.lights)} light(s), "
                                   f"{len(files)} files (see the summary below)")
        self._bundle = (summary, files)
        self._show_summary()
        self.bundle_written.emit(summary)

    def shutdown(self) -> None:
        """Wait for a bundle being written (teardown)."""
        for worker in list(self._workers):
            worker.wait()
