"""The patch window shows an APL patch: a centred window of the screen on a surround colour."""

import threading

import pytest

pytest.importorskip("PySide6")
from workbench.gui.measure_window import patch_window_unavailable_reason  # noqa: E402
from workbench.gui.patch_window import PatchWindow, QtPatchDisplay  # noqa: E402

_UNAVAILABLE = patch_window_unavailable_reason()
if _UNAVAILABLE is not None:  # without a display Qt would abort the whole test process
    pytest.skip(f"Qt cannot open a window here: {_UNAVAILABLE}", allow_module_level=True)

pytestmark = pytest.mark.gui


def _colour_at(window, x, y):
    from PySide6.QtGui import QImage

    image = QImage(window.size(), QImage.Format.Format_RGB32)
    window.render(image)
    colour = image.pixelColor(x, y)
    return [colour.red(), colour.green(), colour.blue()]


def test_an_apl_patch_is_a_centred_window_on_its_surround(qtbot):
    window = PatchWindow(0)
    qtbot.addWidget(window)
    display = QtPatchDisplay(window, timeout_s=5.0)
    qtbot.waitExposed(window)
    errors = []

    def worker():
        try:
            display.show([250, 240, 230], window=0.25, surround=[20, 30, 40])
            assert window.last_painted_frame == ([250, 240, 230], 0.25, [20, 30, 40])
        except Exception as error:  # noqa: BLE001 - reported below
            errors.append(error)

    thread = threading.Thread(target=worker)
    thread.start()
    qtbot.waitUntil(lambda: not thread.is_alive(), timeout=10_000)
    assert errors == []
    rect = window.patch_rect()
    area = rect.width() * rect.height() / (window.width() * window.height())
    assert area == pytest.approx(0.25, rel=0.02)
    assert rect.center().x() == pytest.approx(window.width() / 2, abs=1)
    assert _colour_at(window, window.width() // 2, window.height() // 2) == [250, 240, 230]
    assert _colour_at(window, 1, 1) == [20, 30, 40]
    display.show([9, 9, 9])  # full field again: the surround is gone
    assert _colour_at(window, 1, 1) == [9, 9, 9] and window.frame == ([9, 9, 9], 1.0, [0, 0, 0])
