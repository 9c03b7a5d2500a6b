"""A hidden page redraws once when it is shown, not on every workspace event; a visible one at once."""

from __future__ import annotations

import numpy as np
import pytest

from tests.gui import require_window

require_window("pyqtgraph")

from PySide6.QtWidgets import QWidget  # noqa: E402

from workbench.gui.refresh import RedrawWhenShown  # noqa: E402

pytestmark = pytest.mark.gui


def test_a_hidden_widget_redraws_once_when_shown_and_a_visible_one_at_once(qtbot):
    widget = QWidget()
    qtbot.addWidget(widget)
    drawn = []
    redraw = RedrawWhenShown(widget, lambda: drawn.append(True))
    for _ in range(3):  # session, diagnosis, profile
        redraw()
    assert drawn == [] and redraw.owed
    widget.show()
    assert len(drawn) == 1 and not redraw.owed  # in the show event, before the first paint
    redraw()
    assert len(drawn) == 2
    widget.hide()
    widget.show()  # nothing owed: no redraw
    assert len(drawn) == 2
    redraw()
    redraw.flush()  # visible: drawn at once, nothing left to flush
    assert len(drawn) == 3


def test_the_gamut_page_hidden_during_a_load_shows_the_new_headset_when_opened(window, tmp_path):
    from workbench.gamut import display_gamut
    from workbench.session import write_session_csv
    from workbench.simulated_sessions import simulate_session
    from workbench.workspace import load_path

    gamut = window.page("gamut")
    window.show_page("calibrate")
    assert not gamut.isVisible()
    before = np.column_stack(gamut._headset.getData())
    session = simulate_session({"chromaticity-shift": 0.05}, seed=4, plan="quick")
    loaded = load_path(write_session_csv(session, tmp_path / "session.csv"))
    window.workspace.apply(loaded)
    assert gamut._redraw_when_shown.owed
    np.testing.assert_array_equal(np.column_stack(gamut._headset.getData()), before)  # not redrawn yet
    window.show_page("gamut")
    assert not gamut._redraw_when_shown.owed
    expected = display_gamut(loaded.profile.display_model())
    np.testing.assert_allclose(np.column_stack(gamut._headset.getData())[:-1], expected.xy)
    assert not np.allclose(expected.xy, before[:-1])


def test_the_illuminants_page_hidden_during_a_profile_change_computes_its_rows_and_swatches_when_opened(
        window, qtbot):
    from profiles import example_profile_path
    from workbench.profile import load_profile

    page = window.page("illuminants")
    window.show_page("illuminants")
    assert set(page._comparisons) == set(window.workspace.selected_sources)
    qtbot.waitUntil(lambda: not page.busy, timeout=60000)
    before = page.model.row_of("cie-a").rgb8_profile
    window.show_page("calibrate")
    window.workspace.set_profile(load_profile(example_profile_path("simulated-headset")))
    assert page._profile_when_shown.owed and not page.busy  # put off while hidden: no worker
    window.show_page("illuminants")
    assert not page._profile_when_shown.owed
    assert set(page._comparisons) == set(window.workspace.selected_sources)
    with qtbot.waitSignal(page.rows_ready, timeout=60000):
        pass
    assert page.model.row_of("cie-a").rgb8_profile != before  # the light's RGB for the new headset
