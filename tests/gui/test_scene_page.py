"""The Scene page: both views re-lit in place, read back from VTK, and the error table."""

import numpy as np
import pytest

pytest.importorskip("PySide6")
pytest.importorskip("pyvistaqt")

from workbench.gui.pages.scene import ScenePage  # noqa: E402
from workbench.workspace import Workspace  # noqa: E402

pytestmark = pytest.mark.gui


@pytest.fixture
def page(qtbot):
    page = ScenePage(Workspace())
    qtbot.addWidget(page)
    page.resize(1200, 800)
    page.show()
    qtbot.waitExposed(page)
    yield page
    page.close()


def _views(image):
    half = image.shape[1] // 2
    return image[:, :half], image[:, half:]


def test_level2_view_shows_each_patch_at_its_level2_texture_value(page):
    image = page.rendered_image()
    for level in (1, 2):
        expected = page.level_images(level).patch_rgb8
        for index in (0, 6, 14, 18, 23):
            column, row = page.patch_screen_point(level, index)
            if level == 2:
                assert column >= image.shape[1] // 2  # the right-hand view
            pixel = image[row, column].astype(int)
            assert np.abs(pixel - expected[index]).max() <= 1, (level, index, pixel)


def test_switching_the_source_relights_both_views_and_the_error_table(page, qtbot):
    assert page.source_id == "cie-d65"
    before = page.rendered_image()
    actors = [r.GetActors().GetNumberOfItems() for r in page.plotter.renderers]
    board_image = page._handles[2].board_image
    table_before = page.table.item(1, 0).text()
    summary_before = page.error_summary().summary[1].mean_abs
    # The two-peak metamer has D65's white: level 1 (light colour only) cannot
    # tell them apart, level 2 (re-authored texels) can.
    with qtbot.waitSignal(page.source_changed, timeout=5000):
        page.select_source("d65-two-peak")
    metamer = page.rendered_image()
    (left, right), (left_m, right_m) = _views(before), _views(metamer)
    assert np.abs(left_m.astype(int) - left).mean() < 0.05
    assert np.abs(right_m.astype(int) - right).mean() > 0.3
    assert page.error_summary().source == "d65-two-peak"
    assert page.error_summary().summary[1].mean_abs != summary_before
    assert page.table.item(1, 0).text() != table_before
    with qtbot.waitSignal(page.source_changed, timeout=5000):
        page.select_source("cie-a")
    warm = page.rendered_image()
    for old, new in zip(_views(metamer), _views(warm)):
        assert np.abs(new.astype(int) - old).mean() > 3.0
    assert page.source_box.currentData() == "cie-a"
    # Re-lit in place: the same meshes and texture images, only their pixels changed.
    assert [r.GetActors().GetNumberOfItems() for r in page.plotter.renderers] == actors
    assert page._handles[2].board_image is board_image
    column, row = page.patch_screen_point(2, 0)
    np.testing.assert_allclose(warm[row, column], page.level_images(2).patch_rgb8[0], atol=1)


def test_profile_change_relights(page):
    from dataclasses import replace

    from workbench.display import SRGBDisplay
    from workbench.profile import Profile

    before = page.level_images(1).patch_rgb8.copy()
    srgb = Profile.from_display_model(SRGBDisplay(), device={"name": "ideal sRGB"})
    page.workspace.set_profile(replace(srgb))
    assert np.abs(page.level_images(1).patch_rgb8.astype(int) - before).max() > 2
    assert "ideal sRGB" in page.caption.text()


def test_save_screenshot_shows_the_3d_views(page, tmp_path):
    from PySide6.QtCore import QPoint
    from PySide6.QtGui import QImage

    path = tmp_path / "scene.png"
    page.save_screenshot(path)
    image = QImage(str(path))
    assert (image.width(), image.height()) == (page.width(), page.height())
    for level, index in ((1, 0), (2, 18)):
        column, row = page.patch_screen_point(level, index)
        at = page.plotter.mapTo(page, QPoint(column, row))
        colour = image.pixelColor(at.x(), at.y())
        expected = page.level_images(level).patch_rgb8[index]
        assert abs(colour.red() - int(expected[0])) <= 2, (level, index)
        assert abs(colour.green() - int(expected[1])) <= 2
        assert abs(colour.blue() - int(expected[2])) <= 2


def test_a_source_that_cannot_be_read_is_named_and_another_one_builds_the_views(qtbot, tmp_path, monkeypatch):
    from workbench.illuminants import get_illuminant
    from workbench.illuminants.user_library import USER_LIBRARY_ENV, UserLibrary

    monkeypatch.setenv(USER_LIBRARY_ENV, str(tmp_path / "library"))
    broken = UserLibrary().add(get_illuminant("cie-fl2"), name="tube")
    (tmp_path / "library" / f"{broken}.csv").write_text("wavelength,value\n380,oops\n")
    workspace = Workspace()
    workspace.set_selected_sources([broken, "cie-d65"])
    page = ScenePage(workspace)
    qtbot.addWidget(page)
    page.resize(1200, 800)
    page.show()
    qtbot.waitUntil(lambda: "Cannot show" in page.caption.text())
    assert broken in page.caption.text() and page.plotter is None
    with qtbot.waitSignal(page.source_changed):
        page.select_source(broken)
    assert page.plotter is None
    page.select_source("cie-d65")
    assert page.plotter is not None and page.error_summary().source == "cie-d65"
    assert "Cannot show" not in page.caption.text()
    page.close()
