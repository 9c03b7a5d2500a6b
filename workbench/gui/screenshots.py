"""Render every page of the window to ``DIR/<page>.png`` after a simulated calibration run to the end.

The calibration is the paper's plan on the simulated headset with two
realistic effects (black offset, channel interaction), at a fast time scale,
so that every plot has data and the diagnosis finds something. A page whose
``grab()`` would not show it faithfully (the 3D scene) renders itself with
``save_screenshot(path)``. The window has its default size
(:data:`~workbench.gui.main_window.DEFAULT_SIZE`) unless ``size`` says
otherwise (``gui --screenshot DIR --size 1366x768``).

The Scene page is shown serving its lightbooth to a headset's browser (the
window's WebXR server on loopback, waiting for the headset). Two more views of
the Calibrate page follow the pages: ``calibrate-adaptive.png``, a simulated
run of the adaptive plan to its end (the plan as it grew, the last decision,
the held-out score), and ``calibrate-webxr.png``, a calibration waiting for the
headset's browser (the URL, its QR code and the page's state); that run is
then cancelled.
"""

from __future__ import annotations

import logging
import tempfile
import time
from pathlib import Path

from PySide6.QtCore import QEventLoop, QTimer
from PySide6.QtWidgets import QApplication

from workbench.errors import WorkbenchError
from workbench.gui.main_window import DEFAULT_SIZE, PAGES

__all__ = ["SCREENSHOT_SIZE", "SCREENSHOT_EFFECTS", "EXTRA_SCREENSHOTS", "run_simulated_calibration",
           "save_screenshots"]

SCREENSHOT_SIZE = DEFAULT_SIZE
"""Window size of the screenshots, pixels: the window's default size."""

SCREENSHOT_EFFECTS = {"black-offset": 0.004, "channel-interaction": 0.10}
"""Headset effects of the simulated calibration the screenshots show."""

EXTRA_SCREENSHOTS = ("calibrate-adaptive", "calibrate-webxr")
"""The Calibrate page's views written after the pages' own (module doc)."""

ADAPTIVE_BUDGET_MIN = 13.0
"""The budget of ``calibrate-adaptive.png``'s run, minutes: with :data:`SCREENSHOT_EFFECTS` and seed 2020
the default budget (30 % of the paper plan's time) is spent by the core, and the plan would not grow."""

_TIMEOUT_S = 300.0

_LOG = logging.getLogger(__name__)


def _wait(predicate, timeout_s: float = _TIMEOUT_S, what: str = "") -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise WorkbenchError(f"timed out after {timeout_s:g} s waiting for {what}")
        loop = QEventLoop()
        QTimer.singleShot(20, loop.quit)
        loop.exec()


def run_simulated_calibration(window, out_dir: Path, *, plan: str = "paper", time_scale: float = 0.0,
                              effects: dict | None = None, seed: int = 2020) -> None:
    """Run a simulated calibration in ``window`` to the end and wait for its diagnosis."""
    calibrate = window.pages["calibrate"]
    form = calibrate.form
    form.instrument.setCurrentIndex(0)
    form.display.setCurrentIndex(form.display.findData("simulated"))
    form.plan.setCurrentIndex(form.plan.findData(plan))
    form.seed.setValue(seed)
    form.time_scale.setValue(time_scale)
    for effect_id, (check, magnitude) in form.effects.items():
        wanted = (effects if effects is not None else SCREENSHOT_EFFECTS).get(effect_id)
        check.setChecked(wanted is not None)
        if wanted is not None:
            magnitude.setValue(wanted)
    form.out_dir.setText(str(out_dir))
    QApplication.processEvents()  # the form's changes are shown before the run starts
    loaded, failed = [], []
    calibrate.session_loaded.connect(lambda: loaded.append(True))
    calibrate.error.connect(failed.append)
    calibrate.start()
    _wait(lambda: loaded or failed, what="the simulated calibration and its diagnosis")
    if failed:
        raise WorkbenchError(f"the simulated calibration failed: {failed[0]}")


def save_screenshots(window, directory: Path, *, path=None, time_scale: float | None = None,
                     size: tuple | None = None) -> list:
    """Calibrate (simulated), then write ``directory/<page>.png`` for every page at ``size`` (width,
    height; the window's default size by default); returns the files."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    size = tuple(size or SCREENSHOT_SIZE)
    window.resize(*size)
    window.show()
    QApplication.processEvents()
    with tempfile.TemporaryDirectory(prefix="vr-workbench-screenshots-") as out_dir:
        run_simulated_calibration(window, Path(out_dir) / "session", time_scale=time_scale or 0.0)
        if path:
            loaded = []
            window.file_loaded.connect(loaded.append)
            window.open_path(path)
            _wait(lambda: loaded, what=f"opening {path}")
        written = []
        for key, *_ in PAGES:
            window.show_page(key)
            _wait(lambda: True)
            for _ in range(5):
                QApplication.processEvents()
            page = window.pages[key]
            if callable(getattr(page, "finish_drawing", None)):
                page.finish_drawing()
            window.resize(*size)
            QApplication.processEvents()
            if (window.width(), window.height()) != size:
                _LOG.warning("the %s page does not fit %d×%d: the window is %d×%d", key, *size,
                             window.width(), window.height())
            if key == "export" and callable(getattr(page, "export", None)):
                page.export()  # into the temporary session directory: the page shows what it wrote
                bundles = []
                page.bundle_written.connect(bundles.append)
                page.write_bundle()  # beside the profile, in the temporary session directory
                _wait(lambda: bundles, what="the runtime bundle")
            if key == "scene" and callable(getattr(page, "select_source", None)):
                if callable(getattr(page, "show_in_headset", None)):
                    _serve_scene(window, page)
                # The paper's point: the two-peak D65 metamer looks like D65 at
                # level 1 and shows what it really does to colours at level 2.
                page.select_source("d65-two-peak")
                for _ in range(5):
                    QApplication.processEvents()
            file = directory / f"{key}.png"
            if callable(getattr(page, "save_screenshot", None)):
                page.save_screenshot(file)
            else:
                window.grab().save(str(file))
            written.append(file)
        written += _calibrate_views(window, directory, Path(out_dir), time_scale or 0.0)
    return written


def _start_headset_server(window) -> None:
    """The window's WebXR server on loopback: its default port, or a free one if that is taken."""
    from workbench.errors import InputError
    from workbench.gui.calibration_setup import WEBXR_DEFAULT_ADDRESS

    service = window.headset_browser
    if service.running:
        return
    try:
        service.start(*WEBXR_DEFAULT_ADDRESS)
    except InputError:
        service.start(WEBXR_DEFAULT_ADDRESS[0], 0)


def _serve_scene(window, page) -> None:
    """Serve the Scene page's lightbooth to the headset's browser (the bundle is made in a worker)."""
    _start_headset_server(window)
    page.show_in_headset()
    _wait(lambda: page.serving_scene and page._bundler is None, what="the headset's bundle")
    QApplication.processEvents()


def _calibrate_views(window, directory: Path, out_dir: Path, time_scale: float) -> list:
    """``calibrate-adaptive.png`` and ``calibrate-webxr.png`` (module doc)."""
    page = window.pages["calibrate"]
    form = page.form
    window.show_page("calibrate")
    form.budget.setValue(ADAPTIVE_BUDGET_MIN)
    run_simulated_calibration(window, out_dir / "adaptive", plan="adaptive", time_scale=time_scale)
    _wait(lambda: not page.running, what="the adaptive run's end")
    files = [directory / f"{name}.png" for name in EXTRA_SCREENSHOTS]
    window.show_page("calibrate")  # the loaded session took the window to Fit & diagnose
    QApplication.processEvents()
    window.grab().save(str(files[0]))
    _start_headset_server(window)
    form.display.setCurrentIndex(form.display.findData("webxr"))
    form.plan.setCurrentIndex(form.plan.findData("paper"))
    form.out_dir.setText(str(out_dir / "webxr"))
    QApplication.processEvents()
    page.start()
    window.show_page("calibrate")
    service = window.headset_browser
    _wait(lambda: service.in_use, 30, what="the run to wait for the headset's browser")
    _wait(lambda: "a calibration is waiting for it" in page.headset.state.text(), 10, what="the page's state")
    window.grab().save(str(files[1]))
    page.cancel()
    _wait(lambda: not page.running, 30, what="the cancelled run's end")
    return files
