"""A full-screen patch window: shows calibration patches on a chosen screen.

For headsets in extended mode (the HMD appears as a second monitor) and for
ordinary monitors. :class:`PatchWindow` is a borderless full-screen widget of
one solid colour, or, for an APL patch, a centred rectangle of the screen's
aspect ratio covering the fraction ``window`` of its area on a surround colour,
or the **centring target** (:meth:`PatchWindow.set_target`: white rings at
:data:`TARGET_RING_FRACTIONS` of the smaller side in radius and a cross through
the centre, 2-pixel lines, on black; what the patch protocol's ``target``
draws, to aim the instrument before a run); :class:`QtPatchDisplay` adapts it to the
:class:`~instruments.patch_display.PatchDisplay` protocol, so that the
measurement runner, working off the GUI thread, can call ``show(rgb)`` and get
control back once the window has painted the patch.

The window writes the DAC values straight into its pixels: Qt applies no
colour management to widget painting on X11, Wayland and Windows. (On macOS
the window server may colour-match to the display profile; measure through a
VR application over the TCP patch protocol there.)
"""

from __future__ import annotations

import logging
import threading

from PySide6.QtCore import QMetaObject, QObject, QPointF, QRect, Qt, QThread, Signal, Slot
from PySide6.QtGui import QColor, QGuiApplication, QPainter, QPen
from PySide6.QtWidgets import QWidget

from instruments.patch_display import (PatchDisplayError, is_apl_patch, validate_eye, validate_patch_rgb,
                                       validate_patch_window)
from workbench.errors import InputError

__all__ = ["PatchWindow", "QtPatchDisplay", "screen_names", "TARGET_RING_FRACTIONS", "TARGET_LINE_PX",
           "TARGET_FRAME"]

_LOG = logging.getLogger(__name__)
_FULL_COLOUR_DEPTH = 24  # bits per pixel that carry 8-bit DAC values unchanged

TARGET_RING_FRACTIONS = (0.10, 0.20, 0.30, 0.40)
"""Radii of the centring target's rings, as fractions of the window's smaller side."""
TARGET_LINE_PX = 2
"""Width of the target's rings and cross, pixels."""
TARGET_FRAME = "target"
"""What :attr:`PatchWindow.frame` is while the centring target is shown."""


def screen_names() -> list[str]:
    """Names and geometries of the screens, in the order ``screen_index`` counts them."""
    return [f"{i}: {s.name()} {s.geometry().width()}x{s.geometry().height()}"
            for i, s in enumerate(QGuiApplication.screens())]


class PatchWindow(QWidget):
    """A borderless full-screen window of one solid colour, or of a patch on a surround.

    Parameters
    ----------
    screen_index : int
        Which screen (see :func:`screen_names`); the headset in extended mode
        is usually the last.

    Raises
    ------
    InputError
        If there is no such screen; the message lists the screens.

    Attributes
    ----------
    painted : Signal(list)
        Emitted after each paint with the ``[r, g, b]`` on screen.
    paint_count : int
        How many times the window has painted itself.
    last_painted : list or None
        The ``[r, g, b]`` of the latest paint (``None`` before the first);
        unlike :attr:`rgb`, which :meth:`set_patch` sets before it paints,
        this says what was actually painted.
    """

    painted = Signal(list)

    def __init__(self, screen_index: int = 0):
        super().__init__(None, Qt.WindowType.FramelessWindowHint | Qt.WindowType.WindowStaysOnTopHint)
        screens = QGuiApplication.screens()
        if not 0 <= screen_index < len(screens):
            raise InputError(f"no screen {screen_index}; choose one of: {'; '.join(screen_names())}")
        self.setWindowTitle("vr-workbench patch")
        self.setCursor(Qt.CursorShape.BlankCursor)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        screen = screens[screen_index]
        self.setGeometry(screen.geometry())
        if screen.depth() < _FULL_COLOUR_DEPTH:
            _LOG.warning("screen %s has a colour depth of %d bits: patches will be quantised; "
                         "set it to 24-bit colour before measuring", screen.name(), screen.depth())
        self._rgb = [0, 0, 0]
        self._window = 1.0
        self._surround = [0, 0, 0]
        self._target = False
        self.paint_count = 0
        self.last_painted: list | None = None
        self.last_painted_frame: tuple | None = None

    @property
    def rgb(self) -> list:
        """The DAC values of the patch on screen."""
        return list(self._rgb)

    @property
    def frame(self) -> tuple | str:
        """``(rgb, window, surround)`` of the frame on screen, or :data:`TARGET_FRAME`."""
        if self._target:
            return TARGET_FRAME
        return list(self._rgb), self._window, list(self._surround)

    @Slot()
    def set_target(self) -> None:
        """Show the centring target until the next patch (GUI thread): repaint at once."""
        self._target = True
        self.repaint()

    def target_rings_px(self) -> list:
        """The target's ring radii, pixels: :data:`TARGET_RING_FRACTIONS` of the smaller side."""
        side = min(self.width(), self.height())
        return [fraction * side for fraction in TARGET_RING_FRACTIONS]

    @Slot(list)
    def set_patch(self, rgb: list) -> None:
        """Show ``rgb`` full field (GUI thread): repaint at once."""
        self.set_frame(rgb, 1.0, [0, 0, 0])

    @Slot(list, float, list)
    def set_frame(self, rgb: list, window: float, surround: list) -> None:
        """Show ``rgb`` as ``window`` of the screen's area, centred, on ``surround`` (GUI thread)."""
        self._rgb = validate_patch_rgb(rgb)
        self._window = validate_patch_window(window)
        self._surround = validate_patch_rgb(surround)
        self._target = False
        self.repaint()

    def patch_rect(self):
        """The rectangle the patch fills: centred, the screen's aspect ratio, ``sqrt(window)`` of its sides."""
        rect = self.rect()
        if self._window >= 1.0:
            return rect
        scale = self._window ** 0.5
        width, height = max(1, round(rect.width() * scale)), max(1, round(rect.height() * scale))
        return QRect(rect.x() + (rect.width() - width) // 2, rect.y() + (rect.height() - height) // 2,
                     width, height)

    def _paint_target(self, painter: QPainter) -> None:
        painter.fillRect(self.rect(), QColor(0, 0, 0))
        painter.setRenderHint(QPainter.RenderHint.Antialiasing, False)
        pen = QPen(QColor(255, 255, 255))
        pen.setWidth(TARGET_LINE_PX)
        painter.setPen(pen)
        painter.setBrush(Qt.BrushStyle.NoBrush)
        centre = QPointF(self.width() / 2, self.height() / 2)
        for radius in self.target_rings_px():
            painter.drawEllipse(centre, radius, radius)
        painter.drawLine(QPointF(0, centre.y()), QPointF(self.width(), centre.y()))
        painter.drawLine(QPointF(centre.x(), 0), QPointF(centre.x(), self.height()))

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        painter = QPainter(self)
        if self._target:
            self._paint_target(painter)
            painter.end()
            self.paint_count += 1
            self.last_painted_frame = TARGET_FRAME
            self.painted.emit([])
            return
        if self._window < 1.0:
            painter.fillRect(self.rect(), QColor(*self._surround))
        painter.fillRect(self.patch_rect(), QColor(*self._rgb))
        painter.end()
        self.paint_count += 1
        self.last_painted = list(self._rgb)
        self.last_painted_frame = self.frame
        self.painted.emit(list(self._rgb))


class _Bridge(QObject):
    """Carries ``show`` requests from a worker thread to the GUI thread."""

    request = Signal(list)
    frame_request = Signal(list, float, list)
    target_request = Signal()


class QtPatchDisplay:
    """:class:`~instruments.patch_display.PatchDisplay` over a :class:`PatchWindow`.

    ``show`` may be called from any thread; from a worker it posts the patch to
    the GUI thread and waits (at most ``timeout_s``) until the window has
    painted it.

    Parameters
    ----------
    window : PatchWindow
    timeout_s : float
        Longest wait for the window to paint a patch.
    """

    def __init__(self, window: PatchWindow, timeout_s: float = 5.0):
        self.window = window
        self.timeout_s = float(timeout_s)
        self._bridge = _Bridge()
        self._bridge.moveToThread(window.thread())
        self._bridge.request.connect(window.set_patch, Qt.ConnectionType.QueuedConnection)
        self._bridge.frame_request.connect(window.set_frame, Qt.ConnectionType.QueuedConnection)
        self._bridge.target_request.connect(window.set_target, Qt.ConnectionType.QueuedConnection)
        self._painted = threading.Event()
        self._wanted: tuple | None = None
        window.painted.connect(self._on_painted, Qt.ConnectionType.DirectConnection)
        if not window.isVisible():
            window.showFullScreen()

    def _on_painted(self, rgb: list) -> None:
        if self.window.last_painted_frame == self._wanted:
            self._painted.set()

    def show(self, rgb_dac, window: float = 1.0, surround=(0, 0, 0)) -> None:
        """Show ``rgb_dac`` (as ``window`` of the screen on ``surround``); return once painted."""
        rgb = validate_patch_rgb(rgb_dac)
        if is_apl_patch(window, surround):
            frame = (rgb, validate_patch_window(window), validate_patch_rgb(surround))
        else:
            frame = (rgb, 1.0, [0, 0, 0])
        if QThread.currentThread() is self.window.thread():
            self.window.set_frame(*frame)
            return
        self._painted.clear()
        self._wanted = frame
        if frame[1] < 1.0:
            self._bridge.frame_request.emit(*frame)
        else:
            self._bridge.request.emit(rgb)
        if not self._painted.wait(self.timeout_s):
            raise PatchDisplayError(
                f"the patch window did not paint {rgb} within {self.timeout_s:g} s; "
                "is the GUI event loop running (and the window on a connected screen)?"
            )

    def target(self, eye: str = "both") -> None:
        """Show the centring target (from any thread); return once painted.

        Raises
        ------
        PatchDisplayError
            For ``eye`` left or right: a window on a screen has no eyes.
        """
        if validate_eye(eye) != "both":
            raise PatchDisplayError(f"the patch window cannot show the target to the {eye} eye only: a "
                                    "window covers the whole screen; use --eye both")
        if QThread.currentThread() is self.window.thread():
            self.window.set_target()
            return
        self._painted.clear()
        self._wanted = TARGET_FRAME
        self._bridge.target_request.emit()
        if not self._painted.wait(self.timeout_s):
            raise PatchDisplayError(
                f"the patch window did not paint the centring target within {self.timeout_s:g} s; "
                "is the GUI event loop running (and the window on a connected screen)?"
            )

    def close(self) -> None:
        """Close the window (from the GUI thread, or queued from a worker)."""
        if QThread.currentThread() is self.window.thread():
            self.window.close()
        else:
            QMetaObject.invokeMethod(self.window, "close", Qt.ConnectionType.QueuedConnection)

    def describe(self) -> str:
        screen = self.window.screen()
        return f"full-screen patch window on {screen.name() if screen else 'a screen'}"
