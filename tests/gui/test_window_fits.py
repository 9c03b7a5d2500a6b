"""The window at its default size and at 1366 × 768: nothing clipped, no sideways scrolling.

The Calibrate form fits its column (every button's whole text, every list's current entry, the
estimate wrapped; no horizontal scrollbar; with each patch display, the headset's browser's URL,
QR code and state included, and with the adaptive plan's settings); on Fit & diagnose neither the
findings column nor the validation table scrolls sideways, and what was checked and not found is
a table (effect, z against the critical value, statistic ± SE, impact, in the model or why not;
the evidence as each row's tooltip); the Illuminants page's source table shows every column; the
Export page opens on a summary of what was written with its validation figures, the JSON one
click away.
"""

import gc
import json
import os
import time

import pytest

from tests.gui import require_window

require_window("pyqtgraph")

from PySide6.QtCore import Qt  # noqa: E402
from PySide6.QtWidgets import QAbstractButton, QApplication, QComboBox, QLabel, QWidget  # noqa: E402

from tests.diagnostics.independent_generator import generate_session  # noqa: E402
from workbench.gui import diagnosis_views as views  # noqa: E402
from workbench.gui.main_window import DEFAULT_SIZE, MainWindow  # noqa: E402
from workbench.gui.settings import WindowSettings  # noqa: E402
from workbench.gui.widgets.checked_table import CHECKED_COLUMNS  # noqa: E402
from workbench.gui.widgets_illuminants import CLIPPED_MARK, SOURCE_COLUMNS  # noqa: E402
from workbench.session import write_session_csv  # noqa: E402
from workbench.workspace import Workspace  # noqa: E402

pytestmark = pytest.mark.gui

LOAD_TIMEOUT_MS = 60_000
SIZES = (DEFAULT_SIZE, (1366, 768))  # the window's default size, and a common laptop screen


@pytest.fixture(scope="module")
def knee_csv(tmp_path_factory):
    """A power limit past a knee: findings with a consequence, checked effects, an untestable one."""
    session = generate_session({"channel-interaction": "knee"}, seed=101, plan="paper").session
    return write_session_csv(session, tmp_path_factory.mktemp("knee") / "knee.csv")


def _new_window(directory):
    window = MainWindow(Workspace(), WindowSettings(directory / "config"))
    window.show()
    return window


def _dispose(window) -> None:
    window.shutdown()
    window.close()
    window.deleteLater()
    QApplication.processEvents()
    gc.collect()


@pytest.fixture
def window(qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv("VR_WORKBENCH_CONFIG_DIR", str(tmp_path / "config"))
    window = _new_window(tmp_path)
    yield window
    _dispose(window)


@pytest.fixture(scope="module")
def diagnosed(qapp, knee_csv, tmp_path_factory):
    """One window with the knee session opened and diagnosed (shared: diagnosing takes a while)."""
    directory = tmp_path_factory.mktemp("diagnosed")
    window = _new_window(directory)
    loaded = []
    window.file_loaded.connect(loaded.append)
    window.open_path(knee_csv)
    deadline = time.monotonic() + LOAD_TIMEOUT_MS / 1000
    while not loaded and time.monotonic() < deadline:
        QApplication.processEvents()
        time.sleep(0.01)
    assert loaded, f"{knee_csv} was not opened and diagnosed in {LOAD_TIMEOUT_MS / 1000:g} s"
    yield window
    _dispose(window)


def _settle(window, page: str, size) -> QWidget:
    window.resize(*size)
    window.show_page(page)
    widget = window.pages[page]
    if callable(getattr(widget, "finish_drawing", None)):
        widget.finish_drawing()
    for _ in range(10):
        QApplication.processEvents()
    assert (window.width(), window.height()) == tuple(size)  # nothing on the page is bigger than the screen
    return widget


def _right_edge(widget, ancestor) -> int:
    return widget.mapTo(ancestor, widget.rect().topRight()).x()


@pytest.mark.parametrize("plan", ["paper", "adaptive"])
@pytest.mark.parametrize("display", ["simulated", "window", "tcp", "rgb-text", "value-shot", "webxr"])
@pytest.mark.parametrize("size", SIZES)
def test_the_calibrate_form_fits_its_column_with_every_text_whole(window, size, display, plan):
    page = window.pages["calibrate"]
    form = page.form
    form.webxr_address.setText("127.0.0.1:0")  # a free port, should the headset's browser be chosen
    form.display.setCurrentIndex(form.display.findData(display))
    form.plan.setCurrentIndex(form.plan.findData(plan))
    _settle(window, "calibrate", size)
    scroll = page.form_scroll
    viewport = scroll.viewport()
    assert not scroll.horizontalScrollBar().isVisible()
    assert scroll.horizontalScrollBarPolicy() == Qt.ScrollBarPolicy.ScrollBarAlwaysOff
    assert form.width() <= viewport.width() and form.minimumSizeHint().width() <= viewport.width()

    buttons = [b for b in form.findChildren(QAbstractButton) if b.isVisibleTo(form)]
    texts = {b.text() for b in buttons}
    assert "Find CS-2000" in texts
    assert ("Identify screens" in texts) == (display == "window")  # only the chosen display's settings
    assert ("Test connection" in texts) == (display == "tcp")
    assert ("Stop server" in texts) == (display == "webxr")  # choosing the headset's browser serves its page
    if display == "webxr":  # its URL, QR code and state beside the progress, whole
        panel = page.headset
        assert panel.isVisible() and panel.qr.isVisible() and window.headset_browser.server.url in panel.url.text()
        for label in (panel.url, panel.state):
            assert label.height() >= label.heightForWidth(label.width()), label.text()
            assert _right_edge(label, page) <= page.width(), label.text()
        assert _right_edge(panel.qr, page) <= page.width()
    for field in (form.budget, form.target, form.validation):  # the adaptive plan's settings, with it only
        assert field.isVisibleTo(form) == (plan == "adaptive")
        if plan == "adaptive":
            assert field.sizeHint().width() <= field.width() and _right_edge(field, form) <= viewport.width()
    for button in buttons:
        assert button.sizeHint().width() <= button.width(), button.text()  # the whole text shows
        assert _right_edge(button, form) <= viewport.width(), button.text()
    for combo in form.findChildren(QComboBox):
        if combo.isVisibleTo(form):
            assert combo.text_fits(), combo.currentText()
            assert _right_edge(combo, form) <= viewport.width(), combo.currentText()
    for label in form.findChildren(QLabel):
        if not label.isVisibleTo(form) or not label.text():
            continue
        assert _right_edge(label, form) <= viewport.width(), label.text()
        if label.wordWrap():
            assert label.height() >= label.heightForWidth(label.width()), label.text()  # every line shows
        else:
            assert label.sizeHint().width() <= label.width(), label.text()
    estimate = form.estimate
    assert "patches" in estimate.text() and "instrument time" in estimate.text()
    assert estimate.height() >= 2 * estimate.fontMetrics().height()  # wrapped, not cut at the column's edge
    # the whole form shows without scrolling, even at 1366 × 768
    assert not scroll.verticalScrollBar().isVisible() and form.height() <= viewport.height()


@pytest.mark.parametrize("size", SIZES)
def test_fit_and_diagnose_shows_what_was_checked_as_a_table_and_the_findings_column_fits(diagnosed, size):
    page = _settle(diagnosed, "diagnose", size)
    cards = page.cards
    assert not cards.horizontalScrollBar().isVisible()
    assert cards.widget().width() <= cards.viewport().width()

    document = diagnosed.workspace.diagnosis.to_json()
    checked = [record["effect"] for record in document["checked"]]
    untested = [entry["effect"] for entry in document["untested"] if entry["effect"] not in checked]
    table = page.checked
    assert page.checked_stack.currentWidget() is table and table.isVisible()
    assert [table.horizontalHeaderItem(j).text() for j in range(table.columnCount())] == list(CHECKED_COLUMNS)
    assert table.rowCount() == len(checked) + len(untested) >= 3
    assert [table.item(i, 0).text() for i in range(table.rowCount())] == checked + untested
    records = {record["effect"]: record for record in document["checked"]}
    for i in range(table.rowCount()):
        effect, test, statistic, impact, model = table.row_texts(i)
        record = records.get(effect)
        assert record is None or record["evidence"][:40] in table.item(i, 0).toolTip().replace("&#x27;", "'")
        if record is not None and record["testable"]:
            assert f"{record['critical_z']:.2f}" in test
            if record["z"] is not None:
                assert test.startswith(f"{record['z']:.2f} ")
            assert statistic.startswith(f"{record['statistic']:.3g}") and "±" in statistic
            assert model.startswith("yes" if record["in_model"] else "no")
        else:
            assert model.startswith(("not testable", "not tested")) and "measure plan" in model
    drift = table.row_texts(checked.index("temporal-drift"))
    assert drift[4] == "no: within noise"
    # every row shows (no inner scrolling) and no column is cut off at the side
    assert not table.verticalScrollBar().isVisible() and not table.horizontalScrollBar().isVisible()
    assert table.viewport().height() >= sum(table.rowHeight(i) for i in range(table.rowCount()))
    assert table.horizontalHeader().length() <= table.viewport().width()
    # the other entries of the diagnosis are one click away, in the table's place
    page.details_button.click()
    assert page.checked_stack.currentWidget() is page.details and "noise" in page.details.toPlainText()
    assert "temporal-drift" not in page.details.toPlainText()  # said once, in the table
    page.details_button.click()
    assert page.checked_stack.currentWidget() is table


@pytest.mark.parametrize("size", SIZES)
def test_the_validation_table_shows_every_column_without_scrolling_sideways(diagnosed, size):
    page = _settle(diagnosed, "diagnose", size)
    table = page.table
    assert table.isVisible() and table.rowCount() == 50
    assert not table.horizontalScrollBar().isVisible()
    assert table.horizontalHeader().length() <= table.viewport().width()
    # the worst first, each row's swatch the measured colour and both models' predictions
    assert table.values(2) == sorted(table.values(2), reverse=True)
    icon = table.item(0, 0).icon()
    assert not icon.isNull() and icon.availableSizes()[0].width() == 3 * icon.availableSizes()[0].height()
    assert "baseline" in table.horizontalHeaderItem(0).toolTip()


@pytest.mark.parametrize("size", SIZES)
def test_the_illuminants_table_shows_every_column_without_scrolling_sideways(window, size):
    page = _settle(window, "illuminants", size)
    deadline = time.monotonic() + LOAD_TIMEOUT_MS / 1000
    while page.busy and time.monotonic() < deadline:
        QApplication.processEvents()
        time.sleep(0.01)
    assert not page.busy, "the source table's rows were not computed in time"
    for _ in range(10):
        QApplication.processEvents()
    table, model = page.table, page.model
    assert not table.horizontalScrollBar().isVisible()
    assert table.horizontalHeader().length() <= table.viewport().width()
    name = SOURCE_COLUMNS.index("Name")
    assert table.columnWidth(name) >= table.fontMetrics().horizontalAdvance("CIE FL3.15")  # names readable
    # a long id is elided, and whole in the tooltip
    longest = max(model.ids(), key=len)
    cell = model.index(model.ids().index(longest), 0)
    assert table.columnWidth(0) < table.fontMetrics().horizontalAdvance(longest)
    assert longest in model.data(cell, Qt.ItemDataRole.ToolTipRole)
    # a clipped light RGB is marked, and the mark is explained
    headset = SOURCE_COLUMNS.index("Light RGB (headset)")
    clipped = [i for i, row in enumerate(model.rows()) if not row.light_in_gamut]
    assert clipped and all(model.data(model.index(i, headset)).endswith(CLIPPED_MARK) for i in clipped)
    assert "clipped" in model.data(model.index(clipped[0], headset), Qt.ItemDataRole.ToolTipRole)
    assert f"{CLIPPED_MARK.strip()} after a headset light RGB: clipped" in page.status.text()


def test_checked_rows_give_an_untested_effect_a_row_with_its_reason():
    class _Diagnosis:
        def to_json(self):
            return {"checked": [{"effect": "black-offset", "evidence": "black is 0.4 % of white", "z": 3.1,
                                 "critical_z": 2.33, "statistic": 0.004, "standard_error": 0.001,
                                 "impact_dE00": 0.02, "significant": True, "testable": True, "in_model": False,
                                 "cross_validation": ""}],
                    "untested": [{"effect": "temporal-drift", "reason": "no times in the file"}],
                    "significance": {"materiality_floor_dE00": 0.05}}

    offset, drift = views.checked_rows(_Diagnosis())
    assert (offset.test, offset.statistic, offset.impact) == ("3.10 ≥ 2.33", "0.004 ± 0.001", "0.02")
    assert offset.model == "no: significant but immaterial (impact 0.02 < 0.05 ΔE00)"
    assert (drift.effect, drift.model, drift.testable) == ("temporal-drift", "not tested: no times in the file",
                                                          False)


@pytest.mark.parametrize("size", SIZES)
def test_the_export_page_opens_on_a_summary_with_the_validation_figures_and_the_json_one_click_away(
        qtbot, diagnosed, size, tmp_path):
    page = _settle(diagnosed, "export", size)
    assert page.view.currentWidget() is page.summary
    if size == SIZES[0]:  # the first time (the window is shared)
        assert "No profile written yet" in page.summary.toPlainText()
    written = page.export(tmp_path / "knee.vrprofile.json")
    assert written is not None
    if size == SIZES[0]:
        with qtbot.waitSignal(page.bundle_written, timeout=LOAD_TIMEOUT_MS):
            page.write_bundle(tmp_path / "knee-bundle")
    _settle(diagnosed, "export", size)
    document = json.loads(written.read_text(encoding="utf-8"))
    validation = document["validation"]
    summary = page.summary.toPlainText()
    assert page.view.currentWidget() is page.summary and page.summary.isVisible()
    assert str(written) in summary
    for key in ("mean_dE00", "p95_dE00", "max_dE00"):
        assert f"{validation[key]:.2f}" in summary
    assert "mean ΔE00" in summary and "p95 ΔE00" in summary
    chosen = diagnosed.workspace.diagnosis.to_json()["model_choice"]["chosen"]
    assert f"exported candidate: {chosen}" in summary and document["display_model"]["type"] in summary
    assert f"{len(document['lights'])} lights" in summary
    if size == SIZES[0]:
        assert str(tmp_path / "knee-bundle") in summary and "display_inverse.cube" in summary
    assert not page.summary.horizontalScrollBar().isVisible()
    # one click: the document as written
    qtbot.mouseClick(page.json_button, Qt.MouseButton.LeftButton)
    assert page.view.currentWidget() is page.written and page.written.isVisible()
    assert json.loads(page.written.toPlainText()) == document
    assert page.json_button.sizeHint().width() <= page.json_button.width()
    qtbot.mouseClick(page.json_button, Qt.MouseButton.LeftButton)
    assert page.view.currentWidget() is page.summary


def test_gui_takes_the_window_size_and_refuses_a_size_it_cannot_read():
    from workbench.cli import build_parser
    from workbench.cli.gui import parse_size
    from workbench.errors import WorkbenchError

    args = build_parser().parse_args(["gui", "--screenshot", "out", "--size", "1366x768", "--simulate"])
    assert parse_size(args.size) == (1366, 768) and parse_size("1366×768") == (1366, 768)
    for wrong in ("1366", "1366x", "wide x tall", "10x10"):
        with pytest.raises(WorkbenchError, match="give e.g. 1366x768"):
            parse_size(wrong)


@pytest.mark.slow
def test_gui_screenshot_at_1366_by_768_renders_every_page_at_that_size(tmp_path):
    import subprocess
    import sys

    from PIL import Image

    from workbench.gui.main_window import PAGES

    result = subprocess.run([sys.executable, "-m", "workbench", "gui", "--screenshot", str(tmp_path / "shots"),
                             "--simulate", "--size", "1366x768"], capture_output=True, text=True, timeout=300,
                            env={**os.environ, "VR_WORKBENCH_CONFIG_DIR": str(tmp_path / "config")})
    assert result.returncode == 0, result.stderr[-2000:]
    assert "does not fit" not in result.stderr
    for key, *_ in PAGES:
        image = Image.open(tmp_path / "shots" / f"{key}.png")
        assert image.width == 1366 and image.height <= 768  # the window, or the page within it
