"""The Illuminants page: metrics in a worker, selection, import errors, export, measure, metamer."""

import pytest

pytest.importorskip("PySide6")
pytest.importorskip("pyqtgraph")

from PySide6.QtWidgets import QMessageBox  # noqa: E402

from workbench.gui.pages.illuminants import IlluminantsPage  # noqa: E402
from workbench.illuminants import list_illuminants, read_illuminant_file  # noqa: E402
from workbench.illuminants.user_library import USER_LIBRARY_ENV, UserLibrary  # noqa: E402
from workbench.workspace import Workspace  # noqa: E402

pytestmark = pytest.mark.gui


@pytest.fixture
def errors(monkeypatch):
    shown = []
    monkeypatch.setattr(QMessageBox, "critical",
                        staticmethod(lambda parent, title, text, *a, **k: shown.append((title, text))))
    return shown


@pytest.fixture
def page(qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv(USER_LIBRARY_ENV, str(tmp_path / "library"))
    page = IlluminantsPage(Workspace())
    qtbot.addWidget(page)
    page.resize(1400, 900)
    page.show()
    if page.busy:
        with qtbot.waitSignal(page.rows_ready, timeout=60000):
            pass
    yield page
    page.shutdown()


def test_table_lists_every_source_with_metrics_and_follows_the_workspace(page, qtbot):
    assert page.model.rowCount() == len(list_illuminants())
    row = page.model.row_of("d65-two-peak")
    assert row.Rf < 20 and abs(row.xy[0] - 0.3127) < 1e-3
    assert page.model.row_of("cie-d65").rgb8_srgb == (237, 237, 237)
    assert set(page._selected_ids()) == {"cie-d65", "d65-two-peak"}
    assert [c.source for c in page.swatches._comparisons] == ["cie-d65", "d65-two-peak"]
    page.filter.setText("fl3")
    assert 0 < page.proxy.rowCount() < page.model.rowCount()
    assert page.workspace.selected_sources == ("cie-d65", "d65-two-peak")  # filtering keeps them
    page.filter.setText("")
    page.workspace.set_selected_sources(["cie-a"])
    assert page._selected_ids() == ["cie-a"]
    assert page.plot.curve("cie-a").isVisible() and not page.plot.curve("cie-d65").isVisible()
    # Selecting in the table selects in the workspace.
    page.table.selectRow(page.proxy.mapFromSource(page.model.index(
        page.model.ids().index("cie-fl2"), 0)).row())
    assert page.workspace.selected_sources == ("cie-fl2",)


def test_sorting_by_rf_uses_the_numbers(page):
    column = 5  # Rf
    page.table.sortByColumn(column, page.table.horizontalHeader().sortIndicatorOrder().AscendingOrder)
    values = [float(page.proxy.index(r, column).data()) for r in range(page.proxy.rowCount())]
    assert values == sorted(values)


def test_importing_a_bad_spectrum_file_shows_an_error_naming_the_problem(page, errors, tmp_path):
    bad = tmp_path / "broken.csv"
    bad.write_text("wavelength,value\n380,0.5\n390,-0.2\n400,0.4\n")
    assert page.import_file(bad) is None
    assert len(errors) == 1
    title, text = errors[0]
    assert "broken.csv" in text and "line 3" in text and "negative power" in text
    assert page.last_error == text
    assert UserLibrary().ids() == []


def test_import_and_export_round_trip_into_the_persistent_library(page, errors, tmp_path):
    exported = tmp_path / "fl2.xml"
    page.export_source("cie-fl2", exported)
    assert read_illuminant_file(exported).sd.values.max() > 0
    new_id = page.import_file(exported)
    assert errors == []
    assert new_id in UserLibrary().ids() and page.model.row_of(new_id).kind == "imported"


def test_measuring_a_light_with_the_emulator_adds_it_to_the_library(page, qtbot, errors):
    with qtbot.waitSignal(page.source_added, timeout=30000) as blocker:
        page.measure_light("cie-fl11", "Booth FL11")
    new_id = blocker.args[0]
    assert errors == []
    assert UserLibrary().get(new_id).kind == "measured"
    assert abs(page.model.row_of(new_id).CCT - page.model.row_of("cie-fl11").CCT) < 30
    assert "Lv" in page.status.text()


def test_two_peak_metamer_of_a_source_is_added_and_compared(page, errors):
    new_id = page.synthesize_metamer("cie-d50")
    assert errors == []
    assert page.workspace.selected_sources == ("cie-d50", new_id)
    assert page.model.row_of(new_id).rgb8_profile == page.model.row_of("cie-d50").rgb8_profile
    comparisons = page.swatches._comparisons
    assert comparisons[1].level1_dE00.mean() > comparisons[0].level1_dE00.mean() + 3


def test_profile_change_recomputes_the_headset_light_colour(page, qtbot):
    from workbench.display import SRGBDisplay
    from workbench.profile import Profile

    before = page.model.row_of("cie-a").rgb8_profile
    with qtbot.waitSignal(page.rows_ready, timeout=60000):
        page.workspace.set_profile(Profile.from_display_model(SRGBDisplay(), device={"name": "sRGB"}))
    after = page.model.row_of("cie-a")
    assert after.rgb8_profile == after.rgb8_srgb != before


def test_a_second_profile_change_while_the_rows_compute_waits_for_its_own_rows(page, qtbot):
    from workbench.display import SRGBDisplay
    from workbench.profile import Profile, paper_vive_profile

    total = len(list_illuminants())
    ready = []  # the progress count at each rows_ready
    page.rows_ready.connect(lambda: ready.append(page.progress.value()))
    page.workspace.set_profile(paper_vive_profile())
    page.workspace.set_profile(Profile.from_display_model(SRGBDisplay(), device={"name": "sRGB"}))
    qtbot.waitUntil(lambda: total in ready, timeout=60000)
    qtbot.wait(200)
    assert ready == [total]  # once, when the latest change's rows are all in (not at the superseded job's end)
    assert all(page.model.row_of(i).rgb8_profile == page.model.row_of(i).rgb8_srgb
               for i in page.model.ids())


def test_a_broken_user_library_file_is_named_and_the_rest_listed(qtbot, tmp_path, monkeypatch):
    from workbench.illuminants import get_illuminant

    monkeypatch.setenv(USER_LIBRARY_ENV, str(tmp_path / "library"))
    library = UserLibrary()
    broken = library.add(get_illuminant("cie-fl2"), name="tube")
    (tmp_path / "library" / f"{broken}.csv").write_text("wavelength,value\n380,oops\n")
    page = IlluminantsPage(Workspace())
    qtbot.addWidget(page)
    with qtbot.waitSignal(page.rows_ready, timeout=60000):
        page.show()
    assert page.model.rowCount() == len(list_illuminants())
    assert broken in page.status.text() and "not numeric" in page.status.text()
    page.shutdown()
