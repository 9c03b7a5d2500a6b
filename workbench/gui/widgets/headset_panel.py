"""What the user needs to open the WebXR page in a headset's browser: the URL, its QR code, the page's state.

:class:`QrCode` paints :func:`workbench.vr.terminal_qr.qr_matrix` as an image,
each module a whole number of pixels (crisp, scannable off the screen);
:class:`HeadsetPanel` shows a :class:`~workbench.gui.headset_browser.HeadsetBrowser`'s
URL (a link; selectable), the QR code (inline, or behind a "QR code" button
where room is short) and the connection state in words
(:meth:`~workbench.vr.server.ServerStatus.connection`), following the server
as it changes.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QImage, QPixmap
from PySide6.QtWidgets import (
    QHBoxLayout,
    QLabel,
    QMenu,
    QSizePolicy,
    QToolButton,
    QVBoxLayout,
    QWidget,
    QWidgetAction,
)

__all__ = ["QrCode", "HeadsetPanel", "qr_image"]

_DARK, _LIGHT = QColor("black").rgb(), QColor("white").rgb()


def qr_image(url: str, module_px: int) -> QImage:
    """The QR code of ``url``, ``module_px`` pixels a module (quiet zone included)."""
    from workbench.vr.terminal_qr import qr_matrix

    rows = qr_matrix(url)
    size = len(rows)
    image = QImage(size, size, QImage.Format.Format_RGB32)
    for y, row in enumerate(rows):
        for x, dark in enumerate(row):
            image.setPixel(x, y, _DARK if dark else _LIGHT)
    scale = max(1, int(module_px))
    return image.scaled(size * scale, size * scale, Qt.AspectRatioMode.IgnoreAspectRatio,
                        Qt.TransformationMode.FastTransformation)  # nearest: every module's edge sharp


class QrCode(QLabel):
    """A URL's QR code about ``target_px`` pixels wide (a whole number of pixels a module)."""

    def __init__(self, target_px: int = 100, parent=None):
        super().__init__(parent)
        self.target_px = int(target_px)
        self.url = ""
        self.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.setSizePolicy(QSizePolicy.Policy.Fixed, QSizePolicy.Policy.Fixed)
        self.setToolTip("scan it with the headset's browser (or type the URL)")

    def set_url(self, url: str) -> None:
        self.url = url or ""
        if not self.url:
            self.clear()
            self.setFixedSize(0, 0)
            return
        from workbench.vr.terminal_qr import qr_matrix

        modules = len(qr_matrix(self.url))
        image = qr_image(self.url, max(2, self.target_px // modules))
        self.setPixmap(QPixmap.fromImage(image))
        self.setFixedSize(image.size())

    def modules(self):
        """The painted modules, read back from the pixmap (``True`` = dark), for checks."""
        from workbench.vr.terminal_qr import qr_matrix

        count = len(qr_matrix(self.url))
        image = self.pixmap().toImage()
        step = image.width() // count
        return [[QColor(image.pixel(x * step + step // 2, y * step + step // 2)).lightness() < 128
                 for x in range(count)] for y in range(count)]


class HeadsetPanel(QWidget):
    """The shared server's URL, QR code and page state (module doc).

    Parameters
    ----------
    inline_qr : bool
        The QR code beside the URL (True), or behind a "QR code" button that
        shows it large (False: a page with little height to spare).
    qr_px : int
        The QR code's size, pixels.
    idle_text : str
        What it says while no server runs.
    """

    def __init__(self, *, inline_qr: bool = True, qr_px: int = 100, idle_text: str = "the page is not served",
                 parent=None):
        super().__init__(parent)
        self._service = None
        self.idle_text = idle_text
        self.inline_qr = inline_qr
        self.qr = QrCode(qr_px if inline_qr else 240)
        self.url = QLabel("")
        self.url.setTextFormat(Qt.TextFormat.RichText)
        self.url.setOpenExternalLinks(True)
        self.url.setTextInteractionFlags(Qt.TextInteractionFlag.TextBrowserInteraction)
        self.url.setWordWrap(True)
        self.state = QLabel("")
        self.state.setWordWrap(True)
        self.state.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.note = ""
        if inline_qr:
            layout = QHBoxLayout(self)
            layout.setContentsMargins(0, 0, 0, 0)
            text = QVBoxLayout()
            text.setContentsMargins(0, 0, 0, 0)
            text.addWidget(self.url)
            text.addWidget(self.state)
            text.addStretch(1)
            layout.addWidget(self.qr, 0, Qt.AlignmentFlag.AlignTop)
            layout.addLayout(text, 1)
            self.qr_button = None
        else:
            layout = QHBoxLayout(self)
            layout.setContentsMargins(0, 0, 0, 0)
            self.qr_button = QToolButton(text="QR code")
            self.qr_button.setToolTip("show the URL as a QR code for the headset's browser to scan")
            self.qr_button.setPopupMode(QToolButton.ToolButtonPopupMode.InstantPopup)
            menu = QMenu(self.qr_button)
            action = QWidgetAction(menu)
            holder = QWidget()
            box = QVBoxLayout(holder)
            box.addWidget(self.qr)
            action.setDefaultWidget(holder)
            menu.addAction(action)
            self.qr_button.setMenu(menu)
            self.url.setWordWrap(False)
            self.state.setWordWrap(False)
            self.state.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
            layout.addWidget(self.url)
            layout.addWidget(self.qr_button)
            layout.addWidget(self.state, 1)
        self.show_status(None)

    def bind(self, service) -> None:
        """Follow ``service`` (a :class:`~workbench.gui.headset_browser.HeadsetBrowser`)."""
        if self._service is service:
            return
        if self._service is not None:
            self._service.status_changed.disconnect(self.show_status)
        self._service = service
        service.status_changed.connect(self.show_status)
        self.show_status(service.status())

    def set_note(self, note: str) -> None:
        """A line after the state (e.g. what the Scene page pushed), or ``""``."""
        self.note = note
        self.show_status(self._service.status() if self._service is not None else None)

    def show_problem(self, text: str) -> None:
        """Say why the page is not served (or cannot change), in red, until the next status."""
        self.state.setText(f"<span style='color:#b03a2e'>{text}</span>")
        self.state.setToolTip(text)

    def show_status(self, status) -> None:
        """Show ``status`` (a :class:`~workbench.vr.server.ServerStatus`; ``None``: no server)."""
        if status is None:
            self.url.setText("")
            self.url.setVisible(False)
            self.qr.set_url("")
            if self.inline_qr:
                self.qr.setVisible(False)
            if self.qr_button is not None:
                self.qr_button.setVisible(False)
            self.state.setText(self.idle_text)
            self.state.setToolTip("")
            return
        self.url.setVisible(True)
        self.url.setText(f"open <a href='{status.url}'>{status.url}</a>" + (
            " in the headset's browser" if self.inline_qr else ""))
        self.url.setToolTip(status.url)
        if self.qr.url != status.url:
            self.qr.set_url(status.url)
        if self.inline_qr:
            self.qr.setVisible(True)
        if self.qr_button is not None:
            self.qr_button.setVisible(True)
        text = status.connection()
        if status.patches is not None:
            text += (" — showing a calibration's patches" if status.page.connected and status.page.immersive
                     else " — a calibration is waiting for it")
        if self.note:
            text += f" — {self.note}"
        self.state.setText(text)
        self.state.setToolTip(text)
