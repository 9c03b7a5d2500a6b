"""Run a measurement off the GUI thread while a full-screen patch window shows its patches.

:func:`run_with_patch_window` is what ``measure --display window[:SCREEN]``
calls: Qt owns the main thread (its windows must live there), so the
measurement, which is plain Python with no Qt, runs in a worker thread and
reaches the window through a :class:`~instruments.patch_display.PatchDisplay`
(:class:`~workbench.gui.patch_window.QtPatchDisplay`), while the main thread
pumps the Qt event loop until the worker ends.

Qt cannot report a missing display as an exception: when its platform plugin
cannot connect it aborts the process. :func:`patch_window_unavailable_reason`
therefore asks a short-lived child process first, so that the caller gets an
error it can explain instead of a core dump.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import threading
from typing import Callable, TypeVar

from PySide6.QtCore import QEventLoop, QTimer
from PySide6.QtGui import QGuiApplication
from PySide6.QtWidgets import QApplication

from workbench.errors import WorkbenchError
from workbench.gui.patch_window import PatchWindow, QtPatchDisplay

__all__ = [
    "PatchWindowUnavailableError",
    "WorkerPatchDisplay",
    "patch_window_unavailable_reason",
    "run_with_patch_window",
]

_LOG = logging.getLogger(__name__)

Result = TypeVar("Result")

_SIGNAL_POLL_MS = 100  # the main thread runs Python this often, so a Ctrl-C handler runs promptly
_PROBE_TIMEOUT_S = 60.0
_PROBE = "from PySide6.QtWidgets import QApplication; QApplication(['vr-workbench-probe'])"
_INVISIBLE_PLATFORMS = ("offscreen", "minimal")


class PatchWindowUnavailableError(WorkbenchError):
    """Qt cannot open a window here (no display, or a broken Qt installation); the message says why."""


def patch_window_unavailable_reason() -> str | None:
    """Why Qt could not open a window in this process, or ``None`` if it can.

    Returns ``None`` at once when a ``QApplication`` already exists. Otherwise
    it checks the environment and then creates a ``QApplication`` in a child
    process (about half a second), because Qt aborts the process that fails to
    connect to a display.
    """
    if QApplication.instance() is not None:
        return None
    if (sys.platform.startswith("linux") and not os.environ.get("QT_QPA_PLATFORM")
            and not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY")):
        return "no display: neither DISPLAY nor WAYLAND_DISPLAY is set"
    try:
        probe = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                               timeout=_PROBE_TIMEOUT_S)
    except (OSError, subprocess.TimeoutExpired) as error:
        return f"could not check for a display ({error})"
    if probe.returncode == 0:
        return None
    lines = [line.strip() for line in probe.stderr.splitlines() if line.strip()]
    reasons = [line for line in lines if "display" in line.lower() or "plugin" in line.lower()]
    return (reasons or lines or [f"Qt exited with status {probe.returncode}"])[0]


def _application() -> QApplication:
    """The process's ``QApplication``, created here if there is none yet."""
    app = QApplication.instance()
    if app is None:
        reason = patch_window_unavailable_reason()
        if reason is not None:
            raise PatchWindowUnavailableError(reason)
        app = QApplication([sys.argv[0] if sys.argv else "vr-workbench"])
    elif not isinstance(app, QApplication):
        raise PatchWindowUnavailableError(
            f"this process already runs a {type(app).__name__}, which cannot show widgets")
    if QGuiApplication.platformName() in _INVISIBLE_PLATFORMS:
        _LOG.warning("Qt platform %r draws the patch window off screen; nothing will be visible "
                     "(unset QT_QPA_PLATFORM to show it)", QGuiApplication.platformName())
    return app


class WorkerPatchDisplay:
    """The patch display handed to a worker thread: shows through the window, never closes it.

    Its description is taken in the GUI thread, where the window may be asked
    which screen it is on; whoever opened the window (:func:`run_with_patch_window`,
    the Calibrate page) closes it.
    """

    def __init__(self, display: QtPatchDisplay):
        self._display = display
        self._description = display.describe()

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Show ``rgb_dac`` (as ``window`` of the screen on ``surround``); return once painted."""
        self._display.show(rgb_dac, window=window, surround=surround)

    def target(self, eye: str = "both") -> None:
        """Draw the centring target in the window until the next patch (``measure --target``)."""
        self._display.target(eye)

    def close(self) -> None:
        """Nothing: the window belongs to whoever opened it."""

    def describe(self) -> str:
        """The window and its screen, for the journal header."""
        return self._description


def run_with_patch_window(screen_index: int | None, work: Callable[[object], Result], *,
                          timeout_s: float = 10.0) -> Result:
    """Show a full-screen patch window and run ``work(display)`` in a worker thread.

    The calling (main) thread creates the ``QApplication`` if needed, opens
    the window and pumps Qt's event loop until ``work`` returns; then it
    closes the window and returns what ``work`` returned, or raises what it
    raised.

    Parameters
    ----------
    screen_index : int or None
        The screen to cover (see :func:`~workbench.gui.patch_window.screen_names`);
        ``None``: the last one, which is the headset when it runs in extended mode.
    work : callable
        ``work(display)``, with ``display`` a
        :class:`~instruments.patch_display.PatchDisplay` whose ``show`` may be
        called from the worker. It must not touch Qt.
    timeout_s : float
        Longest wait for the window to paint one patch.

    Returns
    -------
    object
        ``work``'s result.

    Raises
    ------
    PatchWindowUnavailableError
        If Qt cannot open a window here (before ``work`` is started).
    InputError
        If there is no screen ``screen_index``; the message lists the screens.

    Notes
    -----
    The main thread returns to Python every 100 ms, so a ``SIGINT`` handler
    that the caller installed (e.g. one that cancels the measurement) runs
    promptly even while Qt waits for events. Ending the work is the caller's
    business: this function waits for it.
    """
    if threading.current_thread() is not threading.main_thread():
        raise RuntimeError("run_with_patch_window must be called from the main thread (Qt's GUI thread)")
    _application()
    screens = QGuiApplication.screens()
    window = PatchWindow(len(screens) - 1 if screen_index is None else screen_index)
    try:
        display = WorkerPatchDisplay(QtPatchDisplay(window, timeout_s))  # shows the window full screen
        outcome: dict = {}

        def worker() -> None:
            try:
                outcome["result"] = work(display)
            except BaseException as error:  # noqa: BLE001 - re-raised in the main thread
                outcome["error"] = error

        thread = threading.Thread(target=worker, name="measurement", daemon=True)
        loop = QEventLoop()
        poll = QTimer()
        poll.setInterval(_SIGNAL_POLL_MS)
        poll.timeout.connect(lambda: None if thread.is_alive() else loop.quit())
        poll.start()
        thread.start()
        try:
            while thread.is_alive():  # again if something else (QApplication.exit) ended the loop
                loop.exec()
        finally:
            poll.stop()
        thread.join()
    finally:
        window.close()
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]
