"""The full-screen patch window, driven from a worker thread as the runner does."""

import threading

import pytest

from instruments.patch_display import PatchDisplay, PatchDisplayError
from tests.gui import require_window
from workbench.errors import InputError

require_window()

from workbench.gui.patch_window import PatchWindow, QtPatchDisplay, screen_names  # noqa: E402

pytestmark = pytest.mark.gui


def _colour_at(window, x, y):
    """What the window paints at (x, y), at 8 bits per channel whatever the (virtual) screen's depth."""
    from PySide6.QtGui import QImage

    image = QImage(window.size(), QImage.Format.Format_RGB32)
    window.render(image)
    colour = image.pixelColor(x, y)
    return [colour.red(), colour.green(), colour.blue()]


def _colour_at_centre(window):
    return _colour_at(window, window.width() // 2, window.height() // 2)


def test_a_worker_thread_shows_patches_and_gets_control_back_once_painted(qtbot):
    window = PatchWindow(0)
    qtbot.addWidget(window)
    display = QtPatchDisplay(window, timeout_s=5.0)
    assert isinstance(display, PatchDisplay)
    qtbot.waitExposed(window)

    def worker():
        for rgb in ([255, 0, 0], [10, 200, 30]):
            paints = window.paint_count
            display.show(rgb)
            # painted before show returned (window.rgb is set before the paint, so it proves nothing)
            assert window.last_painted == rgb and window.paint_count > paints

    assert _run_in_worker(qtbot, worker) == []
    assert _colour_at_centre(window) == [10, 200, 30]


def test_show_from_the_gui_thread_is_immediate(qtbot):
    window = PatchWindow(0)
    qtbot.addWidget(window)
    display = QtPatchDisplay(window)
    qtbot.waitUntil(lambda: window.paint_count > 0)  # exposed: until then repaint() has nowhere to paint
    paints = window.paint_count
    display.show([1, 2, 3])
    assert window.last_painted == [1, 2, 3] and window.paint_count > paints  # painted before show returned
    assert window.rgb == [1, 2, 3] and _colour_at_centre(window) == [1, 2, 3]


def test_a_window_without_an_event_loop_times_out_with_a_clear_message(qtbot):
    window = PatchWindow(0)
    qtbot.addWidget(window)
    display = QtPatchDisplay(window, timeout_s=0.2)
    errors = []
    thread = threading.Thread(target=lambda: errors.extend(_catch(display.show, [5, 5, 5])))
    thread.start()
    thread.join(5.0)  # the GUI thread is blocked here: nothing can paint
    assert len(errors) == 1 and isinstance(errors[0], PatchDisplayError)
    assert "did not paint [5, 5, 5] within 0.2 s" in str(errors[0])


def _catch(function, *args):
    try:
        function(*args)
    except Exception as error:  # noqa: BLE001
        return [error]
    return []


def _run_in_worker(qtbot, function) -> list:
    """``function`` on a worker thread while the GUI thread's event loop runs; what it raised."""
    errors = []
    thread = threading.Thread(target=lambda: errors.extend(_catch(function)))
    thread.start()
    qtbot.waitUntil(lambda: not thread.is_alive(), timeout=10_000)
    return errors


def test_an_unknown_screen_lists_the_screens(qtbot):
    with pytest.raises(InputError, match="no screen 99; choose one of: 0: "):
        PatchWindow(99)
    assert screen_names()[0].startswith("0: ")


def test_an_apl_patch_is_a_centred_window_on_its_surround(qtbot):
    window = PatchWindow(0)
    qtbot.addWidget(window)
    display = QtPatchDisplay(window, timeout_s=5.0)
    qtbot.waitExposed(window)

    def worker():
        display.show([250, 240, 230], window=0.25, surround=[20, 30, 40])
        assert window.last_painted_frame == ([250, 240, 230], 0.25, [20, 30, 40])

    assert _run_in_worker(qtbot, worker) == []
    rect = window.patch_rect()
    area = rect.width() * rect.height() / (window.width() * window.height())
    assert area == pytest.approx(0.25, rel=0.02)
    assert rect.center().x() == pytest.approx(window.width() / 2, abs=1)
    assert _colour_at(window, window.width() // 2, window.height() // 2) == [250, 240, 230]
    assert _colour_at(window, 1, 1) == [20, 30, 40]
    display.show([9, 9, 9])  # full field again: the surround is gone
    assert _colour_at(window, 1, 1) == [9, 9, 9] and window.frame == ([9, 9, 9], 1.0, [0, 0, 0])


def test_the_centring_target_is_rings_and_a_cross_on_black_until_the_next_patch(qtbot):
    from workbench.gui.patch_window import TARGET_FRAME, TARGET_RING_FRACTIONS

    window = PatchWindow(0)
    qtbot.addWidget(window)
    display = QtPatchDisplay(window, timeout_s=5.0)
    qtbot.waitExposed(window)
    display.show([200, 10, 10])

    def worker():
        display.target()  # from the measurement's thread, as measure --target does
        assert window.last_painted_frame == TARGET_FRAME

    assert _run_in_worker(qtbot, worker) == []
    width, height = window.width(), window.height()
    cx, cy, side = width // 2, height // 2, min(width, height)
    white, black = [255, 255, 255], [0, 0, 0]
    assert window.target_rings_px() == pytest.approx([f * side for f in TARGET_RING_FRACTIONS])
    for fraction in TARGET_RING_FRACTIONS:  # on each ring, right of the centre, away from the cross
        x = round(width / 2 + fraction * side)
        on_ring = [_colour_at(window, x + dx, cy - 0) for dx in (-1, 0)]
        assert white in on_ring, fraction
        between = round(width / 2 + (fraction - 0.05) * side)  # half-way to the ring inside it
        assert _colour_at(window, between, round(height / 2 + 0.3 * (fraction - 0.05) * side)) == black
    assert _colour_at(window, 2, cy) == white or _colour_at(window, 2, cy - 1) == white  # the cross, across
    assert _colour_at(window, cx, 2) == white or _colour_at(window, cx - 1, 2) == white
    assert _colour_at(window, 3, 3) == black
    with pytest.raises(PatchDisplayError, match="cannot show the target to the left eye only"):
        display.target("left")
    display.show([9, 9, 9])  # the next patch replaces it
    assert window.frame == ([9, 9, 9], 1.0, [0, 0, 0]) and _colour_at(window, cx, cy) == [9, 9, 9]
