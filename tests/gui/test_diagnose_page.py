"""Fit & diagnose: the exported model's table, a consequence's card under its cause, and text that wraps.

A power limit past a knee (the independent generator) is opened in the window at the default size and
at 1366 × 768: the page shows the candidates' cross-validated ΔE00 with the exported model marked, the
tone-curve card indented under the interaction's, tagged as its consequence, and no card is wider
than its column (a long evidence line or the follow-up button wraps instead of being clipped).
"""


import pytest

from tests.gui import require_window

require_window("pyqtgraph")

from PySide6.QtWidgets import QApplication, QLabel  # noqa: E402

from tests.diagnostics.independent_generator import generate_session  # noqa: E402
from tests.test_diagnostics import REAL, needs_real_data  # noqa: E402
from workbench.gui.widgets.finding_cards import CONSEQUENCE_INDENT, ModelChoiceTable  # noqa: E402
from workbench.session import write_session_csv  # noqa: E402

pytestmark = pytest.mark.gui

LOAD_TIMEOUT_MS = 60_000
SIZES = ((1500, 950), (1366, 768))  # the window's default size, and a common laptop screen


@pytest.fixture(scope="module")
def knee_csv(tmp_path_factory):
    session = generate_session({"channel-interaction": "knee"}, seed=101, plan="paper").session
    return write_session_csv(session, tmp_path_factory.mktemp("knee") / "knee.csv")


def _open(qtbot, window, path, size):
    with qtbot.waitSignal(window.file_loaded, timeout=LOAD_TIMEOUT_MS):
        window.open_path(path)
    window.show_page("diagnose")
    window.resize(*size)
    page = window.pages["diagnose"]
    page.finish_drawing()
    for _ in range(5):
        QApplication.processEvents()
    return page


@pytest.mark.parametrize("size", SIZES)
def test_the_page_shows_the_exported_model_and_the_consequence_and_wraps_every_text(qtbot, window, knee_csv,
                                                                                   size):
    page = _open(qtbot, window, knee_csv, size)
    assert window.width() == size[0]  # nothing on the page is wider than the screen
    cards = page.cards
    choice = window.workspace.diagnosis.model_choice.to_json()

    table = cards.model_choice
    assert isinstance(table, ModelChoiceTable)
    assert [table.item(i, 0).text().removeprefix(ModelChoiceTable.MARK) for i in range(table.rowCount())] == list(
        choice["cv_mean_dE00"])
    chosen = table.chosen_row()
    assert table.item(chosen, 0).text() == "✓ power-limit" and table.item(chosen, 0).font().bold()
    assert table.item(chosen, 1).text() == f"{choice['cv_mean_dE00']['power-limit']:.3f}"
    assert not any(table.item(i, 0).text().startswith("✓") for i in range(table.rowCount()) if i != chosen)
    assert table.height() >= table.rowCount() * table.rowHeight(0)  # every row shows, no inner scrolling
    assert cards.model_reason.text() == choice["reason"]

    cause, consequence = cards.cards
    assert (cause.card.effect, consequence.card.effect) == ("channel-interaction", "tone-curve-shape")
    body = cards.widget()
    assert consequence.mapTo(body, consequence.rect().topLeft()).x() >= (
        cause.mapTo(body, cause.rect().topLeft()).x() + CONSEQUENCE_INDENT)
    assert consequence.tag is not None and consequence.tag.text() == "consequence of <b>channel-interaction</b>"
    assert consequence.why.text().startswith("← the bend that channel-interaction's power limit")
    assert "a consequence of" not in consequence.evidence.text()
    assert cause.findChild(QLabel, "consequences").text().startswith("explains <b>tone-curve-shape</b>")

    # nothing wider than the column: no horizontal scrolling, the long lines wrap
    assert body.width() <= cards.viewport().width()
    assert not cards.horizontalScrollBar().isVisible()
    for card in cards.cards:
        assert card.mapTo(body, card.rect().topRight()).x() <= cards.viewport().width()
        line = card.evidence.fontMetrics().height()
        assert card.evidence.height() >= 2 * line  # the evidence is long: it wraps to several lines
    button = cards.action_button
    assert button is not None and button.text().startswith("Measure the ")  # the whole text, as before
    assert button.width() <= cause.width()
    label = button.label()
    if label.fontMetrics().horizontalAdvance(button.text()) > label.width():  # too long for one line: wrapped
        assert label.height() >= 2 * label.fontMetrics().height() and button.height() >= label.height()


def test_a_second_diagnosis_keeps_the_plots_numbers_unscaled(qtbot, window, knee_csv, tmp_path):
    """pyqtgraph took an SI scale from the last view's range: 0.4 % residuals read 400 on the next file."""
    other = generate_session({"black-offset": "bluish"}, seed=7, plan="paper").session
    first = write_session_csv(other, tmp_path / "other.csv")
    _open(qtbot, window, first, SIZES[0])
    page = _open(qtbot, window, knee_csv, SIZES[0])
    for plot in page.fits.plots():
        for side in ("left", "bottom"):
            assert plot.getPlotItem().getAxis(side).autoSIPrefixScale == 1.0


@needs_real_data
def test_a_real_session_with_a_grey_ramp_fits_a_1366_screen_and_marks_the_grey_ramp_model(qtbot, window):
    """Four plots under the sweeps (greys as well) made the page 1494 pixels wide."""
    page = _open(qtbot, window, REAL / "lcd-ti3" / "KOIOS_K2418U_2019-04-01_1518_i1d3_417p.ti3", SIZES[1])
    assert window.width() == SIZES[1][0] and page.fits.greys.isVisible()
    table = page.cards.model_choice
    assert table.item(table.chosen_row(), 0).text() == "✓ grey-ramp+sweeps"
    assert table.rowCount() == 4  # baseline, extension, the authors' grey ramp, and it with the sweeps
    assert page.cards.widget().width() <= page.cards.viewport().width()


def test_a_timer_fires_while_the_page_draws_a_diagnosis_part_by_part(qtbot, window, knee_csv):
    """The page draws a diagnosis a part a turn on a timer of its own: a timer due meanwhile (a
    click would be served the same way) runs before the last part is drawn. On a chain of zero
    timers (posted events, all served before any timer) it ran only after the whole page."""
    from PySide6.QtCore import QTimer

    with qtbot.waitSignal(window.file_loaded, timeout=LOAD_TIMEOUT_MS):
        window.open_path(knee_csv)
    window.show_page("diagnose")
    page = window.pages["diagnose"]
    page.finish_drawing()
    old_cards = page.cards.cards
    drawing_when_fired = []
    probe = QTimer()
    probe.setInterval(0)
    probe.timeout.connect(lambda: drawing_when_fired.append(page.cards.cards is old_cards))
    page.show_diagnosis(window.workspace.diagnosis)  # drawn again, as after a new session
    assert page.cards.cards is old_cards  # the first part drawn, the cards waiting for their turns
    probe.start()
    qtbot.waitUntil(lambda: page.cards.cards is not old_cards, timeout=LOAD_TIMEOUT_MS)
    probe.stop()
    assert any(drawing_when_fired), "no timer ran while the page was drawn"
    assert len(page.cards.cards) == 2 and page.cards.model_choice is not None  # all of it drawn
