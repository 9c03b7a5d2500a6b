"""The Gamut page: outlines drawn from the library, coverage shown, validation colours from a diagnosis."""

import numpy as np
import pytest

pytest.importorskip("PySide6")
pytest.importorskip("pyqtgraph")

from workbench.gamut import display_gamut, gamut_coverage, reference_gamut  # noqa: E402
from workbench.gui.pages.gamut import GamutPage  # noqa: E402
from workbench.workspace import Workspace  # noqa: E402

pytestmark = pytest.mark.gui


@pytest.fixture
def page(qtbot):
    page = GamutPage(Workspace())
    qtbot.addWidget(page)
    page.resize(1300, 800)
    page.show()
    return page


def test_shows_the_profiles_gamut_and_its_coverage(page):
    vive = display_gamut(page.workspace.profile.display_model())
    x, y = page._headset.getData()
    np.testing.assert_allclose(np.column_stack([x, y])[:-1], vive.xy)
    expected = gamut_coverage(vive, reference_gamut("DCI-P3"))
    assert page.table.item(1, 0).text() == f"{expected.covered_pct:.1f}"
    assert "DCI-P3" in page.headline.text()
    assert not page._measured.isVisible()
    assert "open a session" in page.validation_label.text()


def test_uv_diagram_changes_axes_and_figures(page):
    xy_figure = page.coverage("Rec. 2020").relative_area_pct
    page.set_diagram("u'v'")
    assert "u′" in page.plot.getPlotItem().getAxis("bottom").labelText
    assert page.coverage("Rec. 2020").diagram == "u'v'"
    assert page.coverage("Rec. 2020").relative_area_pct != pytest.approx(xy_figure, abs=0.1)


def test_reference_outlines_toggle(page):
    page.reference_boxes["sRGB"].setChecked(False)
    assert not page._references["sRGB"].isVisible()
    assert page._references["Rec. 2020"].isVisible()


def test_a_diagnosis_shows_measured_and_predicted_validation_colours(page):
    from workbench.diagnostics import diagnose
    from workbench.simulated_sessions import simulate_session

    session = simulate_session({"channel-interaction": 0.1}, seed=2, plan="quick")
    page.workspace.set_session(session)
    page.workspace.set_diagnosis(diagnose(session))
    n = int(session.mask("validation").sum())
    assert page._measured.isVisible() and len(page._measured.data) == n
    assert len(page._predicted.data) == n
    assert f"{n} patches" in page.validation_label.text()


def test_a_bad_profile_overlay_names_the_file(page, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QMessageBox

    shown = []
    monkeypatch.setattr(QMessageBox, "critical",
                        staticmethod(lambda parent, title, text, *a, **k: shown.append(text)))
    bad = tmp_path / "bad.vrprofile.json"
    bad.write_text("{}")
    page.add_profile_overlay(bad)
    assert len(shown) == 1 and "bad.vrprofile.json" in shown[0]


def _legend_rect_in_data(page):
    """The legend's rectangle in data coordinates (x0, x1, y0, y1)."""
    from PySide6.QtWidgets import QApplication

    for _ in range(10):
        QApplication.processEvents()
    legend, box = page.legend, page.plot.getPlotItem().getViewBox()
    corners = [box.mapSceneToView(legend.mapToScene(point)) for point in
               (legend.boundingRect().topLeft(), legend.boundingRect().bottomRight())]
    xs, ys = sorted(c.x() for c in corners), sorted(c.y() for c in corners)
    return xs[0], xs[1], ys[0], ys[1]


@pytest.mark.parametrize("diagram", ["xy", "u'v'"])
@pytest.mark.parametrize("size", [(1300, 800), (1366, 680)])  # the page at both window sizes
def test_the_legend_covers_no_gamut_outline_and_not_the_locus(page, diagram, size):
    from workbench.gamut import spectral_locus

    page.resize(*size)
    page.set_diagram(diagram)
    x0, x1, y0, y1 = _legend_rect_in_data(page)
    assert x1 - x0 > 0.05 and y1 - y0 > 0.05  # drawn, and somewhere on the plot

    def covered(outline):
        closed = np.vstack([outline, outline[:1]])
        t = np.linspace(0.0, 1.0, 50)[:, None]
        points = np.vstack([a + t * (b - a) for a, b in zip(closed[:-1], closed[1:])])
        return np.sum((points[:, 0] > x0) & (points[:, 0] < x1) & (points[:, 1] > y0) & (points[:, 1] < y1))

    assert covered(spectral_locus(diagram)[1]) == 0
    for name in ("sRGB", "DCI-P3", "Rec. 2020"):
        assert covered(reference_gamut(name).vertices(diagram)) == 0, name
    assert covered(display_gamut(page.workspace.profile.display_model()).vertices(diagram)) == 0
