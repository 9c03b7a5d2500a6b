"""The scene's images and error table (no Qt), and the booth rendered off screen."""

import numpy as np
import pytest

from workbench.colour_management import engine_render, level2_texture, light_colour
from workbench.display import SRGBDisplay
from workbench.illuminants import PAPER_SOURCES, get_illuminant
from workbench.profile import paper_vive_profile
from workbench.reproduction import table4
from workbench.scene import headset_to_monitor_rgb8, level_images, patch_errors, scene_content
from workbench.samples import colorchecker


def test_level2_patch_is_the_engine_output_of_the_level2_texture_as_the_headset_shows_it():
    display = paper_vive_profile().display_model()
    source = get_illuminant("d65-two-peak")
    images = level_images(source, display, 2)
    texture = level2_texture(colorchecker().reflectances, source.sd, display)
    expected = headset_to_monitor_rgb8(engine_render(texture.rgb8, texture.light.rgb8), display)
    np.testing.assert_array_equal(images.patch_rgb8, expected)
    np.testing.assert_array_equal(images.texture_rgb8, texture.rgb8)
    content = scene_content()
    inside = content.board_labels == 7
    assert np.all(images.board[inside] == images.patch_rgb8[7])
    assert np.all(images.board[content.board_labels == -1] == images.board[0, 0])


def test_levels_differ_under_the_metamer_and_agree_on_the_srgb_display_under_d65():
    vive = paper_vive_profile().display_model()
    two_peak = get_illuminant("d65-two-peak")
    level1, level2 = (level_images(two_peak, vive, level) for level in (1, 2))
    assert np.abs(level1.patch_rgb8.astype(int) - level2.patch_rgb8).mean() > 10
    srgb = SRGBDisplay()
    d65 = get_illuminant("cie-d65")
    a, b = (level_images(d65, srgb, level) for level in (1, 2))
    assert np.abs(a.patch_rgb8.astype(int) - b.patch_rgb8).mean() < 4


def test_lamp_is_the_level1_light_colour():
    srgb = SRGBDisplay()
    source = get_illuminant("cie-d50")
    images = level_images(source, srgb, 1)
    np.testing.assert_array_equal(images.light_rgb8, light_colour(source.sd, srgb).rgb8)


def test_unknown_level_is_named():
    with pytest.raises(Exception, match="level"):
        level_images(get_illuminant("cie-d65"), SRGBDisplay(), 3)


def test_patch_errors_summaries_are_the_papers_table4_on_the_srgb_display():
    rows = {(r.source, r.level): r for r in table4()}
    for source in PAPER_SOURCES:
        errors = patch_errors(get_illuminant(source), SRGBDisplay())
        for level in (1, 2):
            expected = rows[(source, level)]
            assert errors.summary[level].mean_abs == pytest.approx(expected.mean_abs)
            assert errors.summary[level].mean_dE00 == pytest.approx(expected.mean_dE00)
            per_patch = np.array([p.abs_dac for p in errors.level(level)])
            assert per_patch.mean(axis=0) == pytest.approx(expected.mean_abs)
        assert errors.paper[1] is not None and len(errors.level(1)) == 24


def test_booth_renders_each_patch_at_its_texture_value_off_screen():
    pv = pytest.importorskip("pyvista")
    from workbench.scene.booth import board_patch_world_point, build_booth, relight_booth

    display = paper_vive_profile().display_model()
    images = level_images(get_illuminant("cie-a"), display, 2)
    plotter = pv.Plotter(off_screen=True, window_size=(640, 400))
    try:
        plotter.disable_anti_aliasing()
        plotter.ren_win.SetMultiSamples(0)
        handles = build_booth(plotter, images)
        first = np.asarray(plotter.screenshot(return_img=True))[..., :3]
        renderer = plotter.renderer
        for index in (0, 11, 18, 23):
            renderer.SetWorldPoint(*board_patch_world_point(handles, index), 1.0)
            renderer.WorldToDisplay()
            x, y, _ = renderer.GetDisplayPoint()
            pixel = first[first.shape[0] - 1 - int(round(y)), int(round(x))]
            assert np.abs(pixel.astype(int) - images.patch_rgb8[index]).max() <= 1, index
        relight_booth(handles, level_images(get_illuminant("d65-two-peak"), display, 2))
        plotter.render()
        second = np.asarray(plotter.screenshot(return_img=True))[..., :3]
        assert np.abs(second.astype(int) - first).mean() > 1.0
    finally:
        plotter.close()
