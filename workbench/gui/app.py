"""``python -m workbench gui``: open the workbench window (or render its pages to PNG files and exit)."""

from __future__ import annotations

import gc
import sys
from pathlib import Path

from PySide6.QtWidgets import QApplication

from workbench.errors import WorkbenchError
from workbench.gui.measure_window import patch_window_unavailable_reason

__all__ = ["application", "build_window", "run_gui"]


def application() -> QApplication:
    """The process's ``QApplication``, created if needed.

    Raises
    ------
    WorkbenchError
        If Qt cannot open a window here (no display); the message says what to do.
    """
    app = QApplication.instance()
    if app is None:
        reason = patch_window_unavailable_reason()
        if reason is not None:
            raise WorkbenchError(f"Qt cannot open a window here ({reason}); run in a desktop session, or "
                                 "under 'xvfb-run -a -s \"-screen 0 1920x1200x24\"' for --screenshot")
        app = QApplication([sys.argv[0] if sys.argv else "vr-workbench"])
        app.setApplicationName("VR colour workbench")
    return app


def build_window(simulate: bool = False, settings=None, *, lazy: bool = False):
    """A :class:`~workbench.gui.main_window.MainWindow` over a new workspace (``lazy``: see the window)."""
    from workbench.gui.main_window import MainWindow
    from workbench.workspace import Workspace

    window = MainWindow(Workspace(), settings, lazy=lazy)
    form = window.pages["calibrate"].form
    if not simulate:
        form.instrument.setCurrentIndex(form.instrument.count() - 1)  # auto: the CS-2000 found by VID/PID
    return window


def run_gui(path: str | None = None, *, simulate: bool = False, screenshot_dir: str | None = None,
            time_scale: float | None = None, size: tuple | None = None) -> int:
    """Show the window (opening ``path`` if given) until it is closed; or, with ``screenshot_dir``,
    run a simulated calibration to the end, render every page to ``DIR/<page>.png`` and exit.
    ``size``: the window's (width, height) in pixels, where not its default."""
    app = application()
    if screenshot_dir is not None:
        import tempfile

        from workbench.gui.screenshots import save_screenshots
        from workbench.gui.settings import WindowSettings

        # A fresh layout, and nothing added to the user's recent files.
        with tempfile.TemporaryDirectory(prefix="vr-workbench-screenshot-settings-") as settings_dir:
            window = build_window(True, WindowSettings(settings_dir))
            written = save_screenshots(window, Path(screenshot_dir), path=path, time_scale=time_scale,
                                       size=size)
            for file in written:
                print(f"wrote {file}")
            _dispose(app, window)
        return 0
    window = build_window(simulate, lazy=True)
    if size is not None:
        window.resize(*size)
    if time_scale is not None:
        window.pages["calibrate"].form.time_scale.setValue(time_scale)
    window.show()
    if path:
        window.open_path(path)
    status = app.exec()
    _dispose(app, window)
    return status


def _dispose(app: QApplication, window) -> None:
    """Close and delete the window, then collect, while Qt is still alive.

    Left to the interpreter's finalization, the order in which PySide6's
    wrappers are collected can abort the process ("none_dealloc") after the
    work is done.
    """
    window.close()
    window.deleteLater()
    app.processEvents()
    del window
    gc.collect()
